//! Scene file parsing and validation.
//!
//! serde reads the file into flat "raw" structs with `deny_unknown_fields` (unknown keys and
//! wrong types come back with line and column); every value is then validated by hand and
//! errors are located by dotted field path (`object[2].radius`) through [`TomlFile::error`].
//! Objects are one flat struct with every possible field, so an unknown `kind` and a field
//! that does not belong to its kind get their own precise messages.

use super::vec3::{cross, norm, normalize, sub};
use super::{
    Camera, Display, ImageSpec, Lens, Light, MAX_RESOLUTION, MAX_TESSELLATION, MIN_TESSELLATION,
    Material, Object, Scene, Shading, Space,
};
use crate::error::FileError;
use crate::files::TomlFile;
use serde::Deserialize;

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
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawImage {
    width: i64,
    height: i64,
    background: Option<f64>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawCamera {
    position: [f64; 3],
    look_at: [f64; 3],
    up: Option<[f64; 3]>,
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
    direction: [f64; 3],
    intensity: Option<f64>,
}

#[derive(Deserialize, Default)]
#[serde(deny_unknown_fields)]
struct RawObject {
    kind: Option<String>,
    space: Option<String>,
    center: Option<[f64; 3]>,
    base: Option<[f64; 3]>,
    axis: Option<[f64; 3]>,
    radius: Option<f64>,
    major_radius: Option<f64>,
    minor_radius: Option<f64>,
    tessellation: Option<i64>,
    capped: Option<bool>,
    vertices: Option<Vec<[f64; 3]>>,
    intensity: Option<toml::Value>,
    from: Option<[f64; 3]>,
    to: Option<[f64; 3]>,
    width: Option<f64>,
    position: Option<[f64; 3]>,
    size: Option<f64>,
    reflectance: Option<f64>,
    specular: Option<f64>,
    shininess: Option<f64>,
    emissive: Option<f64>,
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

/// An allowed range of a real number.
#[derive(Clone, Copy)]
enum Range {
    Any,
    Gt(f64),
    Ge(f64),
    /// `(lo, hi)`
    Open(f64, f64),
    /// `[lo, hi]`
    Closed(f64, f64),
    /// `(lo, hi]`
    LeftOpen(f64, f64),
}

impl Range {
    fn contains(self, x: f64) -> bool {
        x.is_finite()
            && match self {
                Range::Any => true,
                Range::Gt(a) => x > a,
                Range::Ge(a) => x >= a,
                Range::Open(a, b) => x > a && x < b,
                Range::Closed(a, b) => x >= a && x <= b,
                Range::LeftOpen(a, b) => x > a && x <= b,
            }
    }

    fn describe(self) -> String {
        match self {
            Range::Any => "a finite number".into(),
            Range::Gt(a) => format!("a finite number > {a}"),
            Range::Ge(a) => format!("a finite number >= {a}"),
            Range::Open(a, b) => format!("a finite number in ({a}, {b})"),
            Range::Closed(a, b) => format!("a finite number in [{a}, {b}]"),
            Range::LeftOpen(a, b) => format!("a finite number in ({a}, {b}]"),
        }
    }
}

/// Validation context: the file, for locating errors.
struct Ctx<'a> {
    file: &'a TomlFile,
}

impl Ctx<'_> {
    fn err(&self, path: &str, msg: impl Into<String>) -> FileError {
        self.file.error(path, msg)
    }

    fn num(&self, path: &str, x: f64, range: Range) -> R<f64> {
        if range.contains(x) {
            Ok(x)
        } else {
            Err(self.err(path, format!("must be {}, got {x}", range.describe())))
        }
    }

    fn opt(&self, path: &str, x: Option<f64>, default: f64, range: Range) -> R<f64> {
        match x {
            Some(x) => self.num(path, x, range),
            None => Ok(default),
        }
    }

    fn vec3(&self, path: &str, v: [f64; 3]) -> R<[f64; 3]> {
        for (k, c) in v.iter().enumerate() {
            self.num(&format!("{path}[{k}]"), *c, Range::Any)?;
        }
        Ok(v)
    }

    /// A finite, non-zero direction, normalised.
    fn direction(&self, path: &str, v: [f64; 3]) -> R<[f64; 3]> {
        self.vec3(path, v)?;
        let n = norm(v);
        if n > 0.0 && n.is_finite() {
            Ok(normalize(v))
        } else {
            Err(self.err(path, format!("must be a non-zero vector, got {v:?}")))
        }
    }

    /// A finite, non-zero vector kept at its length (cone and cylinder axes).
    fn nonzero(&self, path: &str, v: [f64; 3]) -> R<[f64; 3]> {
        self.direction(path, v)?;
        Ok(v)
    }

    fn int(&self, path: &str, x: i64, lo: u32, hi: u32) -> R<u32> {
        if x >= i64::from(lo) && x <= i64::from(hi) {
            Ok(x as u32)
        } else {
            Err(self.err(path, format!("must be an integer in {lo}..={hi}, got {x}")))
        }
    }

    fn required<T>(&self, path: &str, field: &str, x: Option<T>, what: &str) -> R<T> {
        x.ok_or_else(|| self.err(path, format!("missing field `{field}` ({what})")))
    }
}

pub(super) fn scene_from_toml(file: &TomlFile) -> R<Scene> {
    let raw: RawScene = file.parse()?;
    let c = Ctx { file };
    let name = raw.name.unwrap_or_else(|| stem(&file.name));
    let image = image(&c, &raw.image)?;
    let camera = camera(&c, &raw.camera)?;
    let display = display(&c, raw.display.as_ref())?;
    let shading = match raw.shading {
        Some(s) => Shading {
            ambient: c.opt("shading.ambient", s.ambient, 0.1, Range::Closed(0.0, 1.0))?,
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
                intensity: c.opt(
                    &format!("light[{k}].intensity"),
                    l.intensity,
                    1.0,
                    Range::Ge(0.0),
                )?,
            })
        })
        .collect::<R<Vec<_>>>()?;
    let objects = raw
        .object
        .iter()
        .enumerate()
        .map(|(k, o)| object(&c, &format!("object[{k}]"), o))
        .collect::<R<Vec<_>>>()?;
    Ok(Scene {
        name,
        image,
        camera,
        display,
        shading,
        lights,
        objects,
    })
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
        background: c.opt(
            "image.background",
            r.background,
            0.0,
            Range::Closed(0.0, 1.0),
        )?,
    })
}

fn camera(c: &Ctx, r: &RawCamera) -> R<Camera> {
    let position = c.vec3("camera.position", r.position)?;
    let look_at = c.vec3("camera.look_at", r.look_at)?;
    let view = sub(look_at, position);
    if norm(view) == 0.0 {
        return Err(c.err("camera.look_at", "must differ from camera.position"));
    }
    let up = c.direction("camera.up", r.up.unwrap_or([0.0, 1.0, 0.0]))?;
    // sin of the angle between up and the view direction.
    if norm(cross(normalize(view), up)) < 1e-6 {
        return Err(c.err(
            "camera.up",
            format!("must not be parallel to the view direction (look_at - position = {view:?})"),
        ));
    }
    let fov_y_deg = c.opt(
        "camera.fov_y_deg",
        r.fov_y_deg,
        45.0,
        Range::Open(0.0, 180.0),
    )?;
    let near = c.num("camera.near", r.near, Range::Gt(0.0))?;
    let far = c.num("camera.far", r.far, Range::Any)?;
    if far <= near {
        return Err(c.err(
            "camera.far",
            format!("must be a finite number > camera.near = {near}, got {far}"),
        ));
    }
    let lens = match &r.lens {
        None => Lens::Pinhole,
        Some(l) => lens(c, l)?,
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

fn lens(c: &Ctx, r: &RawLens) -> R<Lens> {
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
        "thin_lens" => {
            let what = "a finite number > 0, scene units";
            let f = c.required("camera.lens", "focal_length", r.focal_length, what)?;
            let focal_length = c.num("camera.lens.focal_length", f, Range::Gt(0.0))?;
            let lens_radius = match (r.f_number, r.lens_radius) {
                (Some(_), Some(_)) => {
                    return Err(c.err(
                        "camera.lens.lens_radius",
                        "give either f_number or lens_radius, not both (lens_radius = focal_length / (2 f_number))",
                    ));
                }
                (Some(n), None) => {
                    focal_length / (2.0 * c.num("camera.lens.f_number", n, Range::Gt(0.0))?)
                }
                (None, Some(rad)) => c.num("camera.lens.lens_radius", rad, Range::Gt(0.0))?,
                (None, None) => {
                    return Err(c.err(
                        "camera.lens",
                        "missing field `f_number` or `lens_radius` (one of them, a finite number > 0)",
                    ));
                }
            };
            let d = c.required(
                "camera.lens",
                "focus_distance",
                r.focus_distance,
                "a finite number > focal_length",
            )?;
            let focus_distance = c.num("camera.lens.focus_distance", d, Range::Any)?;
            if focus_distance <= focal_length {
                return Err(c.err(
                    "camera.lens.focus_distance",
                    format!("must be a finite number > focal_length = {focal_length}, got {focus_distance}"),
                ));
            }
            let deep = c.opt("camera.lens.deep", r.deep, 0.0, Range::Ge(0.0))?;
            let coc = c.opt(
                "camera.lens.coc",
                r.coc,
                Lens::default_coc(focal_length),
                Range::Gt(0.0),
            )?;
            Ok(Lens::ThinLens {
                focal_length,
                lens_radius,
                focus_distance,
                deep,
                coc,
            })
        }
        other => Err(c.err(
            "camera.lens.kind",
            format!("unknown lens kind \"{other}\"; allowed: \"pinhole\", \"thin_lens\""),
        )),
    }
}

fn display(c: &Ctx, r: Option<&RawDisplay>) -> R<Display> {
    let d = Display::default();
    let Some(r) = r else { return Ok(d) };
    Ok(Display {
        contrast: c.opt("display.contrast", r.contrast, d.contrast, Range::Gt(1.0))?,
        gamma: c.opt("display.gamma", r.gamma, d.gamma, Range::LeftOpen(1.0, 5.0))?,
        weber: c.opt("display.weber", r.weber, d.weber, Range::Open(0.0, 1.0))?,
        b_max: c.opt("display.b_max", r.b_max, d.b_max, Range::Gt(0.0))?,
        refresh_hz: c.opt(
            "display.refresh_hz",
            r.refresh_hz,
            d.refresh_hz,
            Range::Gt(0.0),
        )?,
    })
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

fn object(c: &Ctx, p: &str, o: &RawObject) -> R<Object> {
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
    let req = |what: &str| format!("required for kind = \"{kind}\"; {what}");
    let tess = |c: &Ctx| -> R<u32> {
        match o.tessellation {
            Some(t) => c.int(&path("tessellation"), t, MIN_TESSELLATION, MAX_TESSELLATION),
            None => Ok(32),
        }
    };
    let pos_len = |c: &Ctx, f: &str, x: Option<f64>| -> R<f64> {
        let x = c.required(p, f, x, &req("a finite number > 0"))?;
        c.num(&path(f), x, Range::Gt(0.0))
    };
    let point = |c: &Ctx, f: &str, x: Option<[f64; 3]>| -> R<[f64; 3]> {
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
                    format!("must be < major_radius = {major_radius}, got {minor_radius}"),
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
            for (k, v) in vs.iter().enumerate() {
                vertex(c, &format!("{p}.vertices[{k}]"), *v, space)?;
            }
            let intensity = match &o.intensity {
                Some(v) => Some(intensity_list(c, &path("intensity"), v, n)?),
                None if space == Space::Screen => {
                    return Err(c.err(
                        p,
                        format!("missing field `intensity` (required in screen space: an array of {n} numbers >= 0, one per vertex)"),
                    ));
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
                width: c.opt(&path("width"), o.width, 1.0, Range::Gt(0.0))?,
            }
        }
        "light_point" => {
            let position = c.required(p, "position", o.position, &req("[x, y, z]"))?;
            Object::LightPoint {
                space,
                position: vertex(c, &path("position"), position, space)?,
                intensity: scalar_intensity(c, p, kind, o.intensity.as_ref())?,
                size: c.opt(&path("size"), o.size, 1.0, Range::Gt(0.0))?,
            }
        }
        _ => unreachable!("kind checked by allowed()"),
    })
}

/// A vertex: finite; in screen space z (screen depth) in [0, 1].
fn vertex(c: &Ctx, path: &str, v: [f64; 3], space: Space) -> R<[f64; 3]> {
    c.vec3(path, v)?;
    if space == Space::Screen {
        c.num(&format!("{path}[2]"), v[2], Range::Closed(0.0, 1.0))
            .map_err(|mut e| {
                e.msg = format!("{} (screen depth z: 0 = near, 1 = far)", e.msg);
                e
            })?;
    }
    Ok(v)
}

fn material(c: &Ctx, p: &str, o: &RawObject) -> R<Material> {
    let d = Material::default();
    Ok(Material {
        reflectance: c.opt(
            &format!("{p}.reflectance"),
            o.reflectance,
            d.reflectance,
            Range::Closed(0.0, 1.0),
        )?,
        specular: c.opt(
            &format!("{p}.specular"),
            o.specular,
            d.specular,
            Range::Ge(0.0),
        )?,
        shininess: c.opt(
            &format!("{p}.shininess"),
            o.shininess,
            d.shininess,
            Range::Gt(0.0),
        )?,
        emissive: c.opt(
            &format!("{p}.emissive"),
            o.emissive,
            d.emissive,
            Range::Ge(0.0),
        )?,
    })
}

fn value_number(v: &toml::Value) -> Option<f64> {
    match v {
        toml::Value::Float(x) => Some(*x),
        toml::Value::Integer(i) => Some(*i as f64),
        _ => None,
    }
}

fn intensity_list(c: &Ctx, path: &str, v: &toml::Value, n: usize) -> R<Vec<f64>> {
    let what = format!("an array of {n} finite numbers >= 0 (one per vertex)");
    let toml::Value::Array(a) = v else {
        return Err(c.err(path, format!("must be {what}, got {v}")));
    };
    if a.len() != n {
        return Err(c.err(path, format!("must be {what}, got {} values", a.len())));
    }
    a.iter()
        .enumerate()
        .map(|(k, x)| {
            let p = format!("{path}[{k}]");
            let x = value_number(x)
                .ok_or_else(|| c.err(&p, format!("must be a finite number >= 0, got {x}")))?;
            c.num(&p, x, Range::Ge(0.0))
        })
        .collect()
}

fn scalar_intensity(c: &Ctx, p: &str, kind: &str, v: Option<&toml::Value>) -> R<f64> {
    let what = "a finite number >= 0";
    let v = c.required(
        p,
        "intensity",
        v,
        &format!("required for kind = \"{kind}\"; {what}"),
    )?;
    let path = format!("{p}.intensity");
    let x = value_number(v).ok_or_else(|| c.err(&path, format!("must be {what}, got {v}")))?;
    c.num(&path, x, Range::Ge(0.0))
}
