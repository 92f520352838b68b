//! Scene file parsing and validation.
//!
//! serde reads the file into flat "raw" structs with `deny_unknown_fields` (unknown keys and
//! wrong types come back with line and column); every value is then validated by hand and
//! errors are located by dotted field path (`object[2].radius`) through [`TomlFile::error`].
//! Objects are one flat struct with every possible field, so an unknown `kind` and a field
//! that does not belong to its kind get their own precise messages.

use super::vec3::{cross, norm, normalize, sub};
use super::{
    Camera, Display, ImageSpec, Lens, Light, MAX_PRIMITIVES, MAX_RESOLUTION, Object, Rgb, Scene,
    Shading, primitive_count, tessellate,
};
use crate::error::FileError;
use crate::files::TomlFile;
use serde::Deserialize;

mod objects;
mod schema;
mod sequence;

use objects::{RawObject, object};
pub(crate) use schema::hint;
use schema::{
    B_MAX, CONTRAST, COORD, F_NUMBER, FAR_OVER_NEAR, FOV, GAMMA, INTENSITY, LENGTH, LENGTH0,
    REFRESH, Range, UNIT, Vec3, WEBER, num,
};

type R<T> = Result<T, FileError>;

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawScene {
    name: Option<String>,
    image: RawImage,
    camera: RawCamera,
    display: Option<RawDisplay>,
    shading: Option<RawShading>,
    #[serde(default)]
    light: Vec<RawLight>,
    #[serde(default)]
    object: Vec<RawObject>,
    sequence: Option<sequence::RawSequence>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawImage {
    width: i64,
    height: i64,
    background: Option<toml::Value>,
    colour: Option<bool>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawCamera {
    position: Vec3,
    look_at: Vec3,
    up: Option<Vec3>,
    fov_y_deg: Option<f64>,
    near: f64,
    far: f64,
    lens: Option<RawLens>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawLens {
    kind: Option<String>,
    focal_length: Option<f64>,
    f_number: Option<f64>,
    lens_radius: Option<f64>,
    focus_distance: Option<f64>,
    deep: Option<f64>,
    coc: Option<f64>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawDisplay {
    contrast: Option<f64>,
    gamma: Option<f64>,
    weber: Option<f64>,
    b_max: Option<f64>,
    refresh_hz: Option<f64>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawShading {
    ambient: Option<f64>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawLight {
    direction: Vec3,
    intensity: Option<toml::Value>,
}

/// Validation context: the file, for locating errors, and whether any colour was given as
/// an `[r, g, b]` array (the default of `[image] colour`).
struct Ctx<'a> {
    file: &'a TomlFile,
    coloured: std::cell::Cell<bool>,
}

impl Ctx<'_> {
    fn err(&self, path: &str, msg: impl Into<String>) -> FileError {
        self.file.error(path, msg)
    }

    fn num(&self, path: &str, x: f64, range: Range) -> R<f64> {
        if range.contains(x) {
            Ok(x)
        } else {
            Err(self.err(
                path,
                format!("must be {}, got {}", range.describe(), num(x)),
            ))
        }
    }

    /// A colour: a number (grey, R = G = B) or an array `[r, g, b]`, each in `range`.
    fn colour(&self, path: &str, v: Option<&toml::Value>, default: f64, range: Range) -> R<Rgb> {
        let Some(v) = v else {
            return Ok([default; 3]);
        };
        let what = || {
            format!(
                "{} or an array [r, g, b] of three such numbers",
                range.describe()
            )
        };
        let number = |p: &str, x: &toml::Value| match x {
            toml::Value::Float(x) => self.num(p, *x, range),
            toml::Value::Integer(i) => self.num(p, *i as f64, range),
            _ => Err(self.err(p, format!("must be {}, got {x}", what()))),
        };
        match v {
            toml::Value::Array(a) if a.len() == 3 => {
                self.coloured.set(true);
                let mut c = [0.0; 3];
                for (k, x) in a.iter().enumerate() {
                    c[k] = number(&format!("{path}[{k}]"), x)?;
                }
                Ok(c)
            }
            toml::Value::Array(a) => {
                Err(self.err(path, format!("must be {}, got {} values", what(), a.len())))
            }
            x => Ok([number(path, x)?; 3]),
        }
    }

    fn opt(&self, path: &str, x: Option<f64>, default: f64, range: Range) -> R<f64> {
        match x {
            Some(x) => self.num(path, x, range),
            None => Ok(default),
        }
    }

    /// A vector of finite coordinates, each in [`COORD`].
    fn vec3(&self, path: &str, v: Vec3) -> R<[f64; 3]> {
        for (k, c) in v.0.iter().enumerate() {
            self.num(&format!("{path}[{k}]"), *c, COORD)?;
        }
        Ok(v.0)
    }

    /// A finite, non-zero direction, normalised.
    fn direction(&self, path: &str, v: Vec3) -> R<[f64; 3]> {
        let v = self.nonzero(path, v)?;
        Ok(normalize(v))
    }

    /// A finite, non-zero vector kept at its length (cone and cylinder axes).
    fn nonzero(&self, path: &str, v: Vec3) -> R<[f64; 3]> {
        let v = self.vec3(path, v)?;
        let n = norm(v);
        if n > 0.0 && n.is_finite() {
            Ok(v)
        } else {
            Err(self.err(path, format!("must be a non-zero vector, got {v:?}")))
        }
    }

    fn int(&self, path: &str, x: i64, lo: u32, hi: u32) -> R<u32> {
        if x >= i64::from(lo) && x <= i64::from(hi) {
            Ok(x as u32)
        } else {
            Err(self.err(path, format!("must be an integer in {lo}..={hi}, got {x}")))
        }
    }

    /// A required field: missing, the error names `path.field` (located at its table).
    fn required<T>(&self, path: &str, field: &str, x: Option<T>, what: &str) -> R<T> {
        x.ok_or_else(|| {
            let mut e = self.err(path, format!("missing field `{field}` ({what})"));
            e.field = format!("{path}.{field}");
            e
        })
    }
}

pub(super) fn scene_from_toml(file: &TomlFile) -> R<Scene> {
    let raw: RawScene = file
        .parse_with(&hint)
        .map_err(|e| objects::unknown_field_of_kind(file, e))?;
    let c = Ctx {
        file,
        coloured: std::cell::Cell::new(false),
    };
    let name = raw.name.unwrap_or_else(|| stem(&file.name));
    let image = image(&c, &raw.image)?;
    let camera = camera(&c, &raw.camera)?;
    let display = display(&c, raw.display.as_ref())?;
    let shading = match raw.shading {
        Some(s) => Shading {
            ambient: c.opt("shading.ambient", s.ambient, 0.1, UNIT)?,
        },
        None => Shading::default(),
    };
    let lights = raw
        .light
        .iter()
        .enumerate()
        .map(|(k, l)| {
            Ok(Light {
                direction: c.direction(&format!("light[{k}].direction"), l.direction)?,
                intensity: c.colour(
                    &format!("light[{k}].intensity"),
                    l.intensity.as_ref(),
                    1.0,
                    INTENSITY,
                )?,
            })
        })
        .collect::<R<Vec<_>>>()?;
    let objects = raw
        .object
        .iter()
        .enumerate()
        .map(|(k, o)| object(&c, &format!("object[{k}]"), o, (image.width, image.height)))
        .collect::<R<Vec<_>>>()?;
    primitives(&c, &objects)?;
    let sequence = raw
        .sequence
        .as_ref()
        .map(|q| sequence::sequence(&c, q, &camera, &objects, display.refresh_hz))
        .transpose()?;
    let image = ImageSpec {
        colour: raw.image.colour.unwrap_or(c.coloured.get()),
        ..image
    };
    Ok(Scene {
        name,
        image,
        camera,
        display,
        shading,
        lights,
        objects,
        sequence,
        source: crate::files::Source::file(file, None),
    })
}

/// The scene's primitives stay within [`MAX_PRIMITIVES`]: the error names the object that
/// crosses the limit (its tessellation, for a canonical object).
fn primitives(c: &Ctx, objects: &[Object]) -> R<()> {
    let mut total = 0u64;
    for (k, o) in objects.iter().enumerate() {
        let n = primitive_count(o);
        total += n;
        if total > MAX_PRIMITIVES {
            let tessellated = tessellate(o).is_some();
            let field = if tessellated {
                format!("object[{k}].tessellation")
            } else {
                format!("object[{k}]")
            };
            let fix = if tessellated {
                "lower the tessellation of this object or of the ones before it"
            } else {
                "draw fewer objects"
            };
            return Err(c.err(
                &field,
                format!(
                    "the objects up to this one make {total} primitives (this one {n}), more than the {MAX_PRIMITIVES} a scene may have; {fix}"
                ),
            ));
        }
    }
    Ok(())
}

/// `dir/name.toml` -> `name`.
fn stem(name: &str) -> String {
    let base = name.rsplit(['/', '\\']).next().unwrap_or(name);
    base.strip_suffix(".toml").unwrap_or(base).to_string()
}

fn image(c: &Ctx, r: &RawImage) -> R<ImageSpec> {
    Ok(ImageSpec {
        width: c.int("image.width", r.width, 1, MAX_RESOLUTION)?,
        height: c.int("image.height", r.height, 1, MAX_RESOLUTION)?,
        background: c.colour("image.background", r.background.as_ref(), 0.0, UNIT)?,
        colour: false,
    })
}

fn camera(c: &Ctx, r: &RawCamera) -> R<Camera> {
    let position = c.vec3("camera.position", r.position)?;
    let look_at = c.vec3("camera.look_at", r.look_at)?;
    let view = sub(look_at, position);
    if norm(view) == 0.0 {
        return Err(c.err("camera.look_at", "must differ from camera.position"));
    }
    let up = c.direction("camera.up", r.up.unwrap_or(Vec3([0.0, 1.0, 0.0])))?;
    // sin of the angle between up and the view direction.
    if norm(cross(normalize(view), up)) < 1e-6 {
        return Err(c.err(
            "camera.up",
            format!("must not be parallel to the view direction (look_at - position = {view:?})"),
        ));
    }
    let fov_y_deg = c.opt("camera.fov_y_deg", r.fov_y_deg, 45.0, FOV)?;
    let near = c.num("camera.near", r.near, LENGTH)?;
    let far = c.num("camera.far", r.far, LENGTH)?;
    // A view volume at least 0.1 % deep: the background's screen depth 1 / (1 - near / far)
    // (the depth of field's infinity) stays <= 1001.
    if far < FAR_OVER_NEAR * near {
        return Err(c.err(
            "camera.far",
            format!(
                "must be a finite number > camera.near = {}, at least {FAR_OVER_NEAR} camera.near = {} (a view volume at least 0.1 % deep), got {}",
                num(near),
                num(FAR_OVER_NEAR * near),
                num(far)
            ),
        ));
    }
    let lens = match &r.lens {
        None => Lens::Pinhole,
        Some(l) => lens(c, l, near)?,
    };
    Ok(Camera {
        position,
        look_at,
        up,
        fov_y_deg,
        near,
        far,
        lens,
    })
}

fn lens(c: &Ctx, r: &RawLens, near: f64) -> R<Lens> {
    let kind = c.required(
        "camera.lens",
        "kind",
        r.kind.as_deref(),
        "\"pinhole\" or \"thin_lens\"",
    )?;
    match kind {
        "pinhole" => {
            let extra = [
                ("focal_length", r.focal_length.is_some()),
                ("f_number", r.f_number.is_some()),
                ("lens_radius", r.lens_radius.is_some()),
                ("focus_distance", r.focus_distance.is_some()),
                ("deep", r.deep.is_some()),
                ("coc", r.coc.is_some()),
            ];
            if let Some((f, _)) = extra.iter().find(|(_, p)| *p) {
                return Err(c.err(
                    &format!("camera.lens.{f}"),
                    "does not apply to kind = \"pinhole\" (use kind = \"thin_lens\")",
                ));
            }
            Ok(Lens::Pinhole)
        }
        "thin_lens" => thin_lens(c, r, near),
        other => Err(c.err(
            "camera.lens.kind",
            format!("unknown lens kind \"{other}\"; allowed: \"pinhole\", \"thin_lens\""),
        )),
    }
}

/// A thin lens: every length in [`LENGTH`], the aperture no wider than the distance to the
/// near plane (`lens_radius <= near`: a wider one blurs a near object over more than the
/// whole image, and a radius without bound overflows the blur slope to infinity, which turned
/// depth of field off), the plane in focus beyond the focal length.
fn thin_lens(c: &Ctx, r: &RawLens, near: f64) -> R<Lens> {
    let what = LENGTH.describe();
    let f = c.required("camera.lens", "focal_length", r.focal_length, &what)?;
    let focal_length = c.num("camera.lens.focal_length", f, LENGTH)?;
    let wide = |field: &str, radius: f64, fix: String| {
        c.err(
            field,
            format!(
                "gives lens_radius = {} > camera.near = {}: the aperture must not be wider than the distance to the near plane; {fix}",
                num(radius),
                num(near)
            ),
        )
    };
    let lens_radius = match (r.f_number, r.lens_radius) {
        (Some(_), Some(_)) => {
            return Err(c.err(
                "camera.lens.lens_radius",
                "give either f_number or lens_radius, not both (lens_radius = focal_length / (2 f_number))",
            ));
        }
        (Some(n), None) => {
            let n = c.num("camera.lens.f_number", n, F_NUMBER)?;
            let radius = focal_length / (2.0 * n);
            if radius > near {
                let min = focal_length / (2.0 * near);
                return Err(wide(
                    "camera.lens.f_number",
                    radius,
                    format!(
                        "f_number must be >= focal_length / (2 camera.near) = {}",
                        num(min)
                    ),
                ));
            }
            radius
        }
        (None, Some(rad)) => {
            let rad = c.num("camera.lens.lens_radius", rad, LENGTH)?;
            if rad > near {
                return Err(wide(
                    "camera.lens.lens_radius",
                    rad,
                    format!(
                        "use a radius in [{}, {}]",
                        num(crate::scene::MIN_LENGTH),
                        num(near)
                    ),
                ));
            }
            rad
        }
        (None, None) => {
            return Err(c.err(
                "camera.lens",
                format!(
                    "missing field `f_number` or `lens_radius` (one of them: f_number {}, or lens_radius {} and <= camera.near)",
                    F_NUMBER.describe(),
                    LENGTH.describe()
                ),
            ));
        }
    };
    let d = c.required(
        "camera.lens",
        "focus_distance",
        r.focus_distance,
        &format!("{what}, > focal_length"),
    )?;
    let focus_distance = c.num("camera.lens.focus_distance", d, LENGTH)?;
    if focus_distance <= focal_length {
        return Err(c.err(
            "camera.lens.focus_distance",
            format!(
                "must be a finite number > focal_length = {}, got {}",
                num(focal_length),
                num(focus_distance)
            ),
        ));
    }
    let deep = c.opt("camera.lens.deep", r.deep, 0.0, LENGTH0)?;
    let coc = c.opt(
        "camera.lens.coc",
        r.coc,
        Lens::default_coc(focal_length),
        LENGTH,
    )?;
    Ok(Lens::ThinLens {
        focal_length,
        lens_radius,
        focus_distance,
        deep,
        coc,
    })
}

fn display(c: &Ctx, r: Option<&RawDisplay>) -> R<Display> {
    let d = Display::default();
    let Some(r) = r else { return Ok(d) };
    Ok(Display {
        contrast: c.opt("display.contrast", r.contrast, d.contrast, CONTRAST)?,
        gamma: c.opt("display.gamma", r.gamma, d.gamma, GAMMA)?,
        weber: c.opt("display.weber", r.weber, d.weber, WEBER)?,
        b_max: c.opt("display.b_max", r.b_max, d.b_max, B_MAX)?,
        refresh_hz: c.opt("display.refresh_hz", r.refresh_hz, d.refresh_hz, REFRESH)?,
    })
}
