//! What every field of a scene file accepts: the ranges the validation checks and, by dotted
//! field path, the hints that messages from the TOML layer name (`object[2].tessellation`
//! expects `an integer in 3..=1024`). One place for both, so a message never names a range
//! the validation does not apply.

use crate::files::generic_path;
pub(super) use crate::files::num;
use crate::scene::{
    MAX_COORD, MAX_GUARD_BAND, MAX_INTENSITY, MAX_RESOLUTION, MAX_TESSELLATION, MIN_LENGTH,
    MIN_TESSELLATION,
};
use serde::de::{self, Deserializer, IgnoredAny, SeqAccess, Visitor};
use std::fmt;

/// An allowed range of a real number (NaN and infinities are never in it).
#[derive(Clone, Copy)]
pub(super) enum Range {
    /// `[lo, hi]`
    Closed(f64, f64),
    /// `(lo, hi]`
    LeftOpen(f64, f64),
    /// `[lo, hi)`
    RightOpen(f64, f64),
}

impl Range {
    pub(super) fn contains(self, x: f64) -> bool {
        x.is_finite()
            && match self {
                Range::Closed(a, b) => x >= a && x <= b,
                Range::LeftOpen(a, b) => x > a && x <= b,
                Range::RightOpen(a, b) => x >= a && x < b,
            }
    }

    pub(super) fn describe(self) -> String {
        format!("a finite number in {}", self.interval())
    }

    /// The interval alone: `[1e-9, 1e9]`.
    pub(super) fn interval(self) -> String {
        let n = num;
        match self {
            Range::Closed(a, b) => format!("[{}, {}]", n(a), n(b)),
            Range::LeftOpen(a, b) => format!("({}, {}]", n(a), n(b)),
            Range::RightOpen(a, b) => format!("[{}, {})", n(a), n(b)),
        }
    }
}

/// A world coordinate (scene units); screen-space x and y (pixels) too.
pub(super) const COORD: Range = Range::Closed(-MAX_COORD, MAX_COORD);
/// A positive length in scene units (radii, clipping planes, focal length, circle of confusion).
pub(super) const LENGTH: Range = Range::Closed(MIN_LENGTH, MAX_COORD);
/// `camera.far` at least this times `camera.near`.
pub(super) const FAR_OVER_NEAR: f64 = 1.001;
/// A length that may be 0 (the in-focus band's half-width).
pub(super) const LENGTH0: Range = Range::Closed(0.0, MAX_COORD);
/// A fraction (reflectance, ambient, background, screen depth).
pub(super) const UNIT: Range = Range::Closed(0.0, 1.0);
/// An intensity, a specular coefficient or an emission (1 = full white).
pub(super) const INTENSITY: Range = Range::Closed(0.0, MAX_INTENSITY);
/// The Blinn-Phong exponent.
pub(super) const SHININESS: Range = Range::LeftOpen(0.0, 1e6);
/// The vertical field of view in degrees: below 0.001° the projection's scale overflows.
pub(super) const FOV: Range = Range::RightOpen(0.001, 180.0);
/// The f-number `F / (2 R)`.
pub(super) const F_NUMBER: Range = Range::Closed(1e-3, 1e6);
/// The display's contrast `K`: below 2 the log code's tables grow without bound.
pub(super) const CONTRAST: Range = Range::Closed(2.0, 1e9);
/// The display gamma.
pub(super) const GAMMA: Range = Range::LeftOpen(1.0, 5.0);
/// The Weber-Fechner fraction: below 0.001 the grade count is unbounded.
pub(super) const WEBER: Range = Range::Closed(0.001, 0.5);
/// Peak luminance, cd/m².
pub(super) const B_MAX: Range = Range::Closed(0.01, 1e6);
/// Refresh rate, Hz.
pub(super) const REFRESH: Range = Range::Closed(1.0, 1000.0);

/// The largest line width or light-point size (pixels) of a `width x height` image: twice the
/// screen diagonal plus twice the largest guard band on each side. A line or point clipped to
/// the guard band covers the whole screen at that size, so a wider one draws nothing more.
pub(super) fn max_width(width: u32, height: u32) -> f64 {
    let diag = f64::from(width).hypot(f64::from(height));
    2.0 * (diag + 2.0 * f64::from(MAX_GUARD_BAND))
}

/// A colour field: a number in `range` (grey) or an `[r, g, b]` array of them.
fn rgb(range: Range) -> String {
    format!(
        "{} or an array [r, g, b] of three such numbers",
        range.describe()
    )
}

const VEC3: &str = "an array of exactly 3 finite numbers [x, y, z]";

/// What a scene field expects, by dotted path (indices ignored): the message hint of the TOML
/// layer. `None` for a path that is not a field.
pub(crate) fn hint(path: &str) -> Option<String> {
    let g = generic_path(path);
    let vec3 = || format!("{VEC3}, each in {}", COORD.interval());
    // Trailing indices: `camera.position[1]` is an element of a vector,
    // `object[0].vertices[1]` a vertex and `object[0].vertices[1][2]` an element of one.
    let trailing = path.len()
        - path
            .trim_end_matches(|c: char| c.is_ascii_digit() || c == '[' || c == ']')
            .len();
    let indices = path[path.len() - trailing..].matches('[').count();
    let vertex_elem = indices == 1;
    let s = |x: &str| x.to_string();
    Some(match g.as_str() {
        "" => s(
            "a scene: tables [image], [camera] and optionally [display], [shading], [[light]], [[object]]",
        ),
        "name" => s("a string (the scene's name)"),
        "image" => s("a table [image] with width, height and optionally background and colour"),
        "image.width" | "image.height" => {
            format!("an integer in 1..={MAX_RESOLUTION} (pixels)")
        }
        "image.background" => rgb(UNIT),
        "image.colour" => s(
            "a boolean (true: render R, G and B; default: true when any colour is an [r, g, b] array)",
        ),
        "camera" => s(
            "a table [camera] with position, look_at, near, far and optionally up, fov_y_deg, [camera.lens]",
        ),
        "camera.position" | "camera.look_at" | "camera.up" if vertex_elem => COORD.describe(),
        "camera.position" | "camera.look_at" => vec3(),
        "camera.up" => format!("{}, not parallel to the view direction", vec3()),
        "camera.fov_y_deg" => format!("{} (degrees)", FOV.describe()),
        "camera.near" => format!("{} (scene units)", LENGTH.describe()),
        "camera.far" => format!(
            "{} (scene units), >= {FAR_OVER_NEAR} camera.near",
            LENGTH.describe()
        ),
        "camera.lens" => s("a table [camera.lens] with kind = \"pinhole\" or \"thin_lens\""),
        "camera.lens.kind" => s("\"pinhole\" or \"thin_lens\""),
        "camera.lens.focal_length" => format!("{} (scene units)", LENGTH.describe()),
        "camera.lens.f_number" => format!(
            "{}, with focal_length / (2 f_number) <= camera.near",
            F_NUMBER.describe()
        ),
        "camera.lens.lens_radius" => format!("{}, <= camera.near", LENGTH.describe()),
        "camera.lens.focus_distance" => {
            format!("{}, > focal_length", LENGTH.describe())
        }
        "camera.lens.deep" => LENGTH0.describe(),
        "camera.lens.coc" => format!("{} (scene units)", LENGTH.describe()),
        "display" => {
            s("a table [display] with contrast, gamma, weber, b_max, refresh_hz (each optional)")
        }
        "display.contrast" => CONTRAST.describe(),
        "display.gamma" => GAMMA.describe(),
        "display.weber" => WEBER.describe(),
        "display.b_max" => format!("{} (cd/m²)", B_MAX.describe()),
        "display.refresh_hz" => format!("{} (Hz)", REFRESH.describe()),
        "shading" => s("a table [shading] with ambient"),
        "shading.ambient" => UNIT.describe(),
        "light" => s("an array of tables, one [[light]] per light (direction, intensity)"),
        "light.direction" if vertex_elem => COORD.describe(),
        "light.direction" => format!("{}, non-zero", vec3()),
        "light.intensity" => rgb(INTENSITY),
        "object" => s("an array of tables, one [[object]] per object, each with a kind"),
        "object.kind" => s(
            "one of \"sphere\", \"torus\", \"cone\", \"cylinder\", \"triangle\", \"quad\", \"line\", \"light_point\"",
        ),
        "object.space" => s("\"world\" or \"screen\""),
        "object.center" | "object.base" | "object.from" | "object.to" | "object.position"
        | "object.axis"
            if vertex_elem =>
        {
            COORD.describe()
        }
        "object.center" | "object.base" | "object.from" | "object.to" | "object.position" => {
            format!("{} (screen space: x, y in pixels, z in [0, 1])", vec3())
        }
        "object.axis" => format!("{}, non-zero", vec3()),
        "object.radius" | "object.major_radius" | "object.minor_radius" => {
            format!("{} (scene units)", LENGTH.describe())
        }
        "object.tessellation" => {
            format!("an integer in {MIN_TESSELLATION}..={MAX_TESSELLATION}")
        }
        "object.capped" => s("true or false"),
        "object.vertices" if indices == 2 => COORD.describe(),
        "object.vertices" if indices == 1 => vec3(),
        "object.vertices" => format!("an array of 3 (triangle) or 4 (quad) vertices, each {VEC3}"),
        "object.intensity" => format!(
            "{} (line, light_point) or an array of one such intensity per vertex (triangle, quad)",
            rgb(INTENSITY)
        ),
        "object.width" | "object.size" => format!(
            "a finite number in (0, 2 (screen diagonal + {})] pixels",
            2 * MAX_GUARD_BAND
        ),
        "object.reflectance" => rgb(UNIT),
        "object.emissive" => rgb(INTENSITY),
        "object.specular" => INTENSITY.describe(),
        "object.shininess" => SHININESS.describe(),
        _ => return None,
    })
}

/// A 3-vector as written: an array of exactly 3 numbers (serde's `[f64; 3]` ignores extra
/// elements).
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct Vec3(pub(super) [f64; 3]);

impl<'de> serde::Deserialize<'de> for Vec3 {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V;
        impl<'de> Visitor<'de> for V {
            type Value = Vec3;
            fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
                f.write_str(VEC3)
            }
            fn visit_seq<A: SeqAccess<'de>>(self, mut s: A) -> Result<Vec3, A::Error> {
                let mut v = [0.0; 3];
                for (k, x) in v.iter_mut().enumerate() {
                    *x = s
                        .next_element()?
                        .ok_or_else(|| de::Error::invalid_length(k, &self))?;
                }
                let mut n = 3;
                while s.next_element::<IgnoredAny>()?.is_some() {
                    n += 1;
                }
                if n > 3 {
                    return Err(de::Error::invalid_length(n, &self));
                }
                Ok(Vec3(v))
            }
        }
        d.deserialize_seq(V)
    }
}
