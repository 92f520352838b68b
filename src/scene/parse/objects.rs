//! Scene objects: the `[[object]]` tables (one flat raw struct with every possible field,
//! so an unknown `kind` and a field that does not belong to its kind get precise messages),
//! their vertices, materials and intensities.

use super::schema::{INTENSITY, LENGTH, SHININESS, UNIT, Vec3, max_width, num};
use super::{Ctx, R, Range};
use crate::scene::{MAX_TESSELLATION, MIN_TESSELLATION, Material, Object, Rgb, Space};
use serde::Deserialize;

#[derive(Deserialize, Default)]
#[serde(deny_unknown_fields)]
pub(super) struct RawObject {
    kind: Option<String>,
    space: Option<String>,
    center: Option<Vec3>,
    base: Option<Vec3>,
    axis: Option<Vec3>,
    radius: Option<f64>,
    major_radius: Option<f64>,
    minor_radius: Option<f64>,
    tessellation: Option<i64>,
    capped: Option<bool>,
    vertices: Option<Vec<Vec3>>,
    intensity: Option<toml::Value>,
    from: Option<Vec3>,
    to: Option<Vec3>,
    width: Option<f64>,
    position: Option<Vec3>,
    size: Option<f64>,
    reflectance: Option<toml::Value>,
    specular: Option<f64>,
    shininess: Option<f64>,
    emissive: Option<toml::Value>,
}

const KINDS: &str = "\"sphere\", \"torus\", \"cone\", \"cylinder\", \"triangle\", \"quad\", \"line\", \"light_point\"";
const MATERIAL: [&str; 4] = ["reflectance", "specular", "shininess", "emissive"];

impl RawObject {
    /// Names of the fields present in the file, `kind` excluded.
    fn present(&self) -> Vec<&'static str> {
        let flags = [
            ("space", self.space.is_some()),
            ("center", self.center.is_some()),
            ("base", self.base.is_some()),
            ("axis", self.axis.is_some()),
            ("radius", self.radius.is_some()),
            ("major_radius", self.major_radius.is_some()),
            ("minor_radius", self.minor_radius.is_some()),
            ("tessellation", self.tessellation.is_some()),
            ("capped", self.capped.is_some()),
            ("vertices", self.vertices.is_some()),
            ("intensity", self.intensity.is_some()),
            ("from", self.from.is_some()),
            ("to", self.to.is_some()),
            ("width", self.width.is_some()),
            ("position", self.position.is_some()),
            ("size", self.size.is_some()),
            ("reflectance", self.reflectance.is_some()),
            ("specular", self.specular.is_some()),
            ("shininess", self.shininess.is_some()),
            ("emissive", self.emissive.is_some()),
        ];
        flags.iter().filter(|(_, p)| *p).map(|(n, _)| *n).collect()
    }
}

/// The fields each kind accepts (besides `kind`).
fn allowed(kind: &str) -> Option<&'static [&'static str]> {
    Some(match kind {
        "sphere" => &[
            "center",
            "radius",
            "tessellation",
            "reflectance",
            "specular",
            "shininess",
            "emissive",
        ],
        "torus" => &[
            "center",
            "axis",
            "major_radius",
            "minor_radius",
            "tessellation",
            "reflectance",
            "specular",
            "shininess",
            "emissive",
        ],
        "cone" | "cylinder" => &[
            "base",
            "axis",
            "radius",
            "tessellation",
            "capped",
            "reflectance",
            "specular",
            "shininess",
            "emissive",
        ],
        "triangle" | "quad" => &[
            "space",
            "vertices",
            "intensity",
            "reflectance",
            "specular",
            "shininess",
            "emissive",
        ],
        "line" => &["space", "from", "to", "intensity", "width"],
        "light_point" => &["space", "position", "intensity", "size"],
        _ => return None,
    })
}

/// An unknown field of an `[[object]]` (serde's message lists the fields of every kind):
/// the fields of the object's own `kind`, when the file gives a known one.
pub(super) fn unknown_field_of_kind(
    file: &crate::files::TomlFile,
    mut e: crate::error::FileError,
) -> crate::error::FileError {
    let Some(rest) = e.field.strip_prefix("object[") else {
        return e;
    };
    let Some((index, name)) = rest.split_once("].") else {
        return e;
    };
    if name.contains(['.', '[']) || !e.msg.starts_with("unknown field") {
        return e;
    }
    let kind = toml::from_str::<toml::Table>(&file.text)
        .ok()
        .and_then(|t| {
            let objects = t.get("object")?.as_array()?;
            let o = objects.get(index.parse::<usize>().ok()?)?;
            Some(o.get("kind")?.as_str()?.to_string())
        });
    if let Some((kind, fields)) = kind.and_then(|k| Some((k.clone(), allowed(&k)?))) {
        let list: Vec<String> = std::iter::once("kind")
            .chain(fields.iter().copied())
            .map(|f| format!("`{f}`"))
            .collect();
        e.msg = format!(
            "unknown field `{name}` for an object of kind \"{kind}\"; allowed: {} (check the spelling)",
            list.join(", ")
        );
    }
    e
}

/// One `[[object]]` of an image of `size = (width, height)` pixels (which bounds line widths
/// and light-point sizes).
pub(super) fn object(c: &Ctx, p: &str, o: &RawObject, size: (u32, u32)) -> R<Object> {
    let kind = c.required(p, "kind", o.kind.as_deref(), &format!("one of {KINDS}"))?;
    let Some(fields) = allowed(kind) else {
        return Err(c.err(
            &format!("{p}.kind"),
            format!("unknown object kind \"{kind}\"; allowed: {KINDS}"),
        ));
    };
    for f in o.present() {
        if !fields.contains(&f) {
            return Err(c.err(
                &format!("{p}.{f}"),
                format!(
                    "does not apply to kind = \"{kind}\" (its fields: {})",
                    fields.join(", ")
                ),
            ));
        }
    }
    let path = |f: &str| format!("{p}.{f}");
    // Line width and light-point size, pixels: a wider one covers nothing more.
    let wide = Range::LeftOpen(0.0, max_width(size.0, size.1));
    let req = |what: &str| format!("required for kind = \"{kind}\"; {what}");
    let tess = |c: &Ctx| -> R<u32> {
        match o.tessellation {
            Some(t) => c.int(&path("tessellation"), t, MIN_TESSELLATION, MAX_TESSELLATION),
            None => Ok(32),
        }
    };
    let pos_len = |c: &Ctx, f: &str, x: Option<f64>| -> R<f64> {
        let x = c.required(p, f, x, &req(&LENGTH.describe()))?;
        c.num(&path(f), x, LENGTH)
    };
    let point = |c: &Ctx, f: &str, x: Option<Vec3>| -> R<[f64; 3]> {
        let x = c.required(p, f, x, &req("[x, y, z]"))?;
        c.vec3(&path(f), x)
    };
    let space = match o.space.as_deref() {
        None | Some("world") => Space::World,
        Some("screen") => Space::Screen,
        Some(s) => {
            return Err(c.err(
                &path("space"),
                format!("unknown space \"{s}\"; allowed: \"world\", \"screen\""),
            ));
        }
    };
    Ok(match kind {
        "sphere" => Object::Sphere {
            center: point(c, "center", o.center)?,
            radius: pos_len(c, "radius", o.radius)?,
            tessellation: tess(c)?,
            material: material(c, p, o)?,
        },
        "torus" => {
            let axis = c.required(p, "axis", o.axis, &req("a non-zero vector [x, y, z]"))?;
            let major_radius = pos_len(c, "major_radius", o.major_radius)?;
            let minor_radius = pos_len(c, "minor_radius", o.minor_radius)?;
            if minor_radius >= major_radius {
                return Err(c.err(
                    &path("minor_radius"),
                    format!(
                        "must be < major_radius = {}, got {}",
                        num(major_radius),
                        num(minor_radius)
                    ),
                ));
            }
            Object::Torus {
                center: point(c, "center", o.center)?,
                axis: c.direction(&path("axis"), axis)?,
                major_radius,
                minor_radius,
                tessellation: tess(c)?,
                material: material(c, p, o)?,
            }
        }
        "cone" | "cylinder" => {
            let base = point(c, "base", o.base)?;
            let axis = c.required(p, "axis", o.axis, &req("a non-zero vector [x, y, z]"))?;
            let axis = c.nonzero(&path("axis"), axis)?;
            let radius = pos_len(c, "radius", o.radius)?;
            let tessellation = tess(c)?;
            let capped = o.capped.unwrap_or(true);
            let material = material(c, p, o)?;
            if kind == "cone" {
                Object::Cone {
                    base,
                    axis,
                    radius,
                    tessellation,
                    capped,
                    material,
                }
            } else {
                Object::Cylinder {
                    base,
                    axis,
                    radius,
                    tessellation,
                    capped,
                    material,
                }
            }
        }
        "triangle" | "quad" => {
            let n = if kind == "triangle" { 3 } else { 4 };
            let what = format!("an array of {n} vertices [x, y, z]");
            let vs = c.required(p, "vertices", o.vertices.as_ref(), &req(&what))?;
            if vs.len() != n {
                return Err(c.err(
                    &path("vertices"),
                    format!("must be {what}, got {} vertices", vs.len()),
                ));
            }
            let vs = vs
                .iter()
                .enumerate()
                .map(|(k, v)| vertex(c, &format!("{p}.vertices[{k}]"), *v, space))
                .collect::<R<Vec<_>>>()?;
            let intensity = match &o.intensity {
                Some(v) => Some(intensity_list(c, &path("intensity"), v, n)?),
                None if space == Space::Screen => {
                    let mut e = c.err(
                        p,
                        format!("missing field `intensity` (required in screen space: an array of {n} numbers in [0, {}], one per vertex)", num(crate::scene::MAX_INTENSITY)),
                    );
                    e.field = path("intensity");
                    return Err(e);
                }
                None => None,
            };
            if intensity.is_some()
                && let Some(f) = MATERIAL.iter().find(|f| o.present().contains(f))
            {
                return Err(c.err(
                    &path(f),
                    "has no effect: the vertices' intensity is given, so the surface is not shaded",
                ));
            }
            let material = material(c, p, o)?;
            if n == 3 {
                Object::Triangle {
                    space,
                    vertices: [vs[0], vs[1], vs[2]],
                    intensity: intensity.map(|i| [i[0], i[1], i[2]]),
                    material,
                }
            } else {
                Object::Quad {
                    space,
                    vertices: [vs[0], vs[1], vs[2], vs[3]],
                    intensity: intensity.map(|i| [i[0], i[1], i[2], i[3]]),
                    material,
                }
            }
        }
        "line" => {
            let from = c.required(p, "from", o.from, &req("[x, y, z]"))?;
            let to = c.required(p, "to", o.to, &req("[x, y, z]"))?;
            Object::Line {
                space,
                from: vertex(c, &path("from"), from, space)?,
                to: vertex(c, &path("to"), to, space)?,
                intensity: scalar_intensity(c, p, kind, o.intensity.as_ref())?,
                width: pixels(c, &path("width"), o.width, wide)?,
            }
        }
        "light_point" => {
            let position = c.required(p, "position", o.position, &req("[x, y, z]"))?;
            Object::LightPoint {
                space,
                position: vertex(c, &path("position"), position, space)?,
                intensity: scalar_intensity(c, p, kind, o.intensity.as_ref())?,
                size: pixels(c, &path("size"), o.size, wide)?,
            }
        }
        _ => unreachable!("kind checked by allowed()"),
    })
}

/// A line width or light-point size in pixels (default 1), in `wide`: the bound keeps the
/// footprint and the raster's loops finite.
fn pixels(c: &Ctx, path: &str, x: Option<f64>, wide: Range) -> R<f64> {
    let x = x.unwrap_or(1.0);
    if wide.contains(x) {
        return Ok(x);
    }
    Err(c.err(
        path,
        format!(
            "must be {} pixels (twice the screen diagonal plus twice the largest guard band, {} pixels, on each side: a wider one covers nothing more), got {}",
            wide.describe(),
            crate::scene::MAX_GUARD_BAND,
            num(x)
        ),
    ))
}

/// A vertex: every coordinate in [`super::schema::COORD`]; in screen space z (screen
/// depth) in [0, 1].
fn vertex(c: &Ctx, path: &str, v: Vec3, space: Space) -> R<[f64; 3]> {
    let v = c.vec3(path, v)?;
    if space == Space::Screen {
        c.num(&format!("{path}[2]"), v[2], UNIT).map_err(|mut e| {
            e.msg = format!("{} (screen depth z: 0 = near, 1 = far)", e.msg);
            e
        })?;
    }
    Ok(v)
}

fn material(c: &Ctx, p: &str, o: &RawObject) -> R<Material> {
    let d = Material::default();
    Ok(Material {
        reflectance: c.colour(
            &format!("{p}.reflectance"),
            o.reflectance.as_ref(),
            d.reflectance[0],
            UNIT,
        )?,
        specular: c.opt(&format!("{p}.specular"), o.specular, d.specular, INTENSITY)?,
        shininess: c.opt(
            &format!("{p}.shininess"),
            o.shininess,
            d.shininess,
            SHININESS,
        )?,
        emissive: c.colour(
            &format!("{p}.emissive"),
            o.emissive.as_ref(),
            d.emissive[0],
            INTENSITY,
        )?,
    })
}

fn intensity_list(c: &Ctx, path: &str, v: &toml::Value, n: usize) -> R<Vec<Rgb>> {
    let what = format!(
        "an array of {n} intensities (one per vertex), each a finite number in [0, {}] or an [r, g, b] array of them",
        num(crate::scene::MAX_INTENSITY)
    );
    let toml::Value::Array(a) = v else {
        return Err(c.err(path, format!("must be {what}, got {v}")));
    };
    if a.len() != n {
        return Err(c.err(path, format!("must be {what}, got {} values", a.len())));
    }
    a.iter()
        .enumerate()
        .map(|(k, x)| c.colour(&format!("{path}[{k}]"), Some(x), 0.0, INTENSITY))
        .collect()
}

fn scalar_intensity(c: &Ctx, p: &str, kind: &str, v: Option<&toml::Value>) -> R<Rgb> {
    let what = INTENSITY.describe();
    let v = c.required(
        p,
        "intensity",
        v,
        &format!("required for kind = \"{kind}\"; {what} or an [r, g, b] array of them"),
    )?;
    c.colour(&format!("{p}.intensity"), Some(v), 0.0, INTENSITY)
}
