//! Per-vertex shading in f64 (docs/reference.md §5): Lambert plus Blinn-Phong.

use super::vec3::{add, dot, normalize, sub};
use super::{Light, Material, Rgb};

/// Linear intensity of a surface point, per channel (R, G, B; a grey scene's three are equal):
///
/// `i = emissive + reflectance * (ambient + Σ_l I_l·max(0, n·l))
///        + specular * Σ_l I_l·max(0, n·h)^shininess`
///
/// with `n` the unit normal, `l` the unit direction towards light l,
/// `h = normalize(e + l)` and `e` the unit direction from the point to the eye. The specular
/// term is not gated by `n·l` (as written in docs/reference.md §5); when `e + l` vanishes (light
/// exactly behind the point as seen from the eye) that light's specular term is 0.
/// `normal` need not be unit length; light directions are expected unit (they are normalised
/// on load).
pub fn shade_vertex(
    position: [f64; 3],
    normal: [f64; 3],
    eye: [f64; 3],
    material: &Material,
    ambient: f64,
    lights: &[Light],
) -> Rgb {
    let n = normalize(normal);
    let e = normalize(sub(eye, position));
    let mut diffuse = [ambient; 3];
    let mut spec = [0.0; 3];
    for light in lights {
        let l = light.direction;
        let lambert = dot(n, l).max(0.0);
        let phong = if material.specular != 0.0 {
            let s = add(e, l);
            (dot(s, s) > 1e-24).then(|| dot(n, normalize(s)).max(0.0).powf(material.shininess))
        } else {
            None
        };
        for c in 0..3 {
            diffuse[c] += light.intensity[c] * lambert;
            if let Some(p) = phong {
                spec[c] += light.intensity[c] * p;
            }
        }
    }
    std::array::from_fn(|c| {
        material.emissive[c] + material.reflectance[c] * diffuse[c] + material.specular * spec[c]
    })
}
