//! The scene file and the host front end (the only f64 geometry in the crate).
//!
//! A scene (TOML, see `src/scene/default.toml` for a commented example) describes the image,
//! the camera (pinhole or thin lens), the display, the lights and the objects. [`front_end`]
//! turns it into screen-space [`Primitive`]s with per-vertex linear intensity: it tessellates
//! the canonical objects, culls back faces of closed ones, shades vertices (Lambert +
//! Blinn-Phong, docs/reference.md §5), clips against the near and far planes in view space, projects,
//! and clips against the guard band in screen space. The fixed-point pipeline quantises the
//! result.
//!
//! Conventions:
//! * World space is right-handed; the camera looks from `position` to `look_at` with `up`
//!   giving the screen's upward direction and a vertical field of view; aspect = width/height
//!   (square pixels).
//! * Screen space: x, y in pixels, origin at the top-left corner, y down; pixel (px, py)
//!   covers `[px, px+1) x [py, py+1)` and its centre is `(px + 0.5, py + 0.5)`. The optical
//!   axis goes through `(width/2, height/2)`.
//! * Screen depth z is affine in screen space: `z = (1/near - 1/d) / (1/near - 1/far)` with
//!   d the view-space depth (distance along the view axis), so z = 0 at near and 1 at far.

mod anim;
mod meshes;
mod parse;
mod project;
mod shade;
mod tessellate;
mod vec3;

use crate::error::FileError;
use crate::files::{Source, TomlFile};
use serde::Serialize;

pub use anim::{CameraKey, Interpolation, ObjectKey, Sequence, interpolate};
pub use meshes::MeshCache;
pub use project::{
    LensPoint, depth_from_screen_z, front_end, front_end_in, front_end_through, screen_z,
};
pub use shade::shade_vertex;
pub use tessellate::{Mesh, primitive_count, tessellate};

/// Largest accepted image width and height, in pixels (`image.width`, `image.height` are in
/// `1..=MAX_RESOLUTION`).
pub const MAX_RESOLUTION: u32 = 8192;

/// Smallest accepted tessellation level of a canonical object.
pub const MIN_TESSELLATION: u32 = 3;

/// Largest accepted tessellation level of a canonical object.
pub const MAX_TESSELLATION: u32 = 1024;

/// Largest magnitude of a world coordinate and largest length (radius, clipping plane, focal
/// length), in scene units; screen-space x and y (pixels) have the same bound. Beyond it the
/// front end's products of coordinates lose the precision it needs.
pub const MAX_COORD: f64 = 1e9;

/// Smallest positive length in scene units (radius, clipping plane, focal length, lens radius,
/// circle of confusion): below it `1 / near` and the projection's scale leave f64's range.
pub const MIN_LENGTH: f64 = 1e-9;

/// Largest intensity (light, vertex, line, light point), specular coefficient and emission;
/// 1 = full white.
pub const MAX_INTENSITY: f64 = 1e6;

/// Largest guard band of the hardware beyond each screen edge, in pixels (`raster.guard_band`
/// is in `0..=MAX_GUARD_BAND`). It bounds the line widths and light-point sizes of a scene:
/// at most `2 (screen diagonal + 2 MAX_GUARD_BAND)` pixels.
pub const MAX_GUARD_BAND: u32 = 4096;

/// Most primitives a scene may put into the front end (tessellated triangles, raw triangles
/// (a quad counts 2), lines and light points): four spheres at the largest tessellation. It
/// bounds the host's and the pipeline's per-primitive memory (a few hundred bytes each).
pub const MAX_PRIMITIVES: u64 = 1 << 22;

/// A linear RGB triple (R, G, B): a colour or an intensity per channel. A grey value is
/// three equal components.
pub type Rgb = [f64; 3];

/// Embedded scenes by name: `(name, TOML text)`. [`Scene::embedded`] looks names up here.
pub const EMBEDDED: &[(&str, &str)] = &[
    ("default", include_str!("default.toml")),
    ("cone-focus", include_str!("cone-focus.toml")),
    ("default-colour", include_str!("default-colour.toml")),
    ("flypast", include_str!("flypast.toml")),
];

/// Every name [`Scene::embedded`] knows: the [`EMBEDDED`] files and `default-pinhole` (the
/// default scene with a pinhole camera), in the order the README lists them.
pub fn names() -> Vec<&'static str> {
    let mut v: Vec<&'static str> = EMBEDDED.iter().map(|(n, _)| *n).collect();
    v.insert(1, "default-pinhole");
    v
}

/// A whole scene: what to draw, how to look at it and on which display.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Scene {
    /// Name of the scene (`name` in the file; else the file's stem).
    pub name: String,
    /// Resolution and background.
    pub image: ImageSpec,
    /// Viewpoint, projection and lens.
    pub camera: Camera,
    /// The display the image is shown on.
    pub display: Display,
    /// Global shading parameters.
    pub shading: Shading,
    /// Directional lights.
    pub lights: Vec<Light>,
    /// Objects, drawn in this order.
    pub objects: Vec<Object>,
    /// The keyframes of an animated scene (`[sequence]`; [`Scene::frame`] gives a frame).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub sequence: Option<Sequence>,
    /// The file it was read from: later checks locate its fields ([`Scene::error`]).
    #[serde(skip)]
    pub source: Source,
}

/// Image size and background (`[image]`).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ImageSpec {
    /// Width in pixels, `1..=MAX_RESOLUTION`.
    pub width: u32,
    /// Height in pixels, `1..=MAX_RESOLUTION`.
    pub height: u32,
    /// Linear intensity of the background at infinity, each channel in `[0, 1]` (default 0).
    pub background: Rgb,
    /// Whether the scene is rendered in colour (three channels, R, G, B): `[image] colour`,
    /// by default true when any colour of the file is given as an `[r, g, b]` array.
    pub colour: bool,
}

/// The display model (`[display]`, every field optional).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Display {
    /// Contrast `K = B_max / B_min`, in `[2, 1e9]` (default 100).
    pub contrast: f64,
    /// Display gamma, in `(1, 5]` (default 2.4).
    pub gamma: f64,
    /// Weber–Fechner fraction δ, in `[0.001, 0.5]` (default 0.02).
    pub weber: f64,
    /// Peak luminance in cd/m², in `[0.01, 1e6]` (default 100).
    pub b_max: f64,
    /// Refresh rate in Hz, in `[1, 1000]` (default 60).
    pub refresh_hz: f64,
}

impl Display {
    /// Luminance of black (stray light), `B_min = B_max / K`.
    pub fn b_min(&self) -> f64 {
        self.b_max / self.contrast
    }
}

impl Default for Display {
    /// K = 100, γ = 2.4, δ = 0.02, B_max = 100 cd/m², 60 Hz.
    fn default() -> Self {
        Self {
            contrast: 100.0,
            gamma: 2.4,
            weber: 0.02,
            b_max: 100.0,
            refresh_hz: 60.0,
        }
    }
}

/// The camera's lens (`[camera.lens]`, `kind = "pinhole"` or `"thin_lens"`; absent = pinhole).
#[derive(Clone, Debug, PartialEq, Serialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum Lens {
    /// Everything in focus.
    Pinhole,
    /// Thin lens (docs/reference.md §2). All lengths in scene units.
    ThinLens {
        /// Focal length F, in `[MIN_LENGTH, MAX_COORD]`.
        focal_length: f64,
        /// Lens (aperture) radius R, in `[MIN_LENGTH, near]`: no wider than the distance to
        /// the near plane. In the file either `lens_radius` or `f_number` (in `[0.001, 1e6]`)
        /// (then `lens_radius = focal_length / (2 f_number)`).
        lens_radius: f64,
        /// Distance of the plane in focus, > `focal_length`, at most `MAX_COORD`.
        focus_distance: f64,
        /// Half-width of the in-focus band around `focus_distance`, in `[0, MAX_COORD]`
        /// (default 0).
        deep: f64,
        /// Permissible circle of confusion, in `[MIN_LENGTH, MAX_COORD]` (default
        /// `0.035 * focal_length / 50`: the 35 mm film standard of 0.035 mm at F = 50 mm,
        /// scaled with the focal length).
        coc: f64,
    },
}

impl Lens {
    /// The default permissible circle of confusion for a focal length: `0.035 * F / 50`.
    pub fn default_coc(focal_length: f64) -> f64 {
        0.035 * focal_length / 50.0
    }
}

/// The camera (`[camera]`).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Camera {
    /// Eye position, world space.
    pub position: [f64; 3],
    /// Point looked at; differs from `position`.
    pub look_at: [f64; 3],
    /// Upward direction (default `[0, 1, 0]`); not parallel to the view direction.
    pub up: [f64; 3],
    /// Vertical field of view in degrees, in `[0.001, 180)` (default 45).
    pub fov_y_deg: f64,
    /// Near clipping distance along the view axis, in `[MIN_LENGTH, MAX_COORD]`.
    pub near: f64,
    /// Far clipping distance along the view axis, at least `1.001 near`, at most `MAX_COORD`.
    pub far: f64,
    /// The lens.
    pub lens: Lens,
}

/// Global shading parameters (`[shading]`).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Shading {
    /// Ambient light c_a, in `[0, 1]` (default 0.1).
    pub ambient: f64,
}

impl Default for Shading {
    /// Ambient 0.1.
    fn default() -> Self {
        Self { ambient: 0.1 }
    }
}

/// A directional light (`[[light]]`).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Light {
    /// Direction towards the light, world space, normalised on load.
    pub direction: [f64; 3],
    /// Intensity I_l per channel, in `[0, MAX_INTENSITY]` (default 1: white).
    pub intensity: Rgb,
}

/// Surface reflection parameters; flat fields of an `[[object]]`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Material {
    /// Diffuse reflectance c_r per channel, in `[0, 1]` (default 0.8).
    pub reflectance: Rgb,
    /// Specular coefficient, in `[0, MAX_INTENSITY]` (default 0).
    pub specular: f64,
    /// Blinn-Phong exponent p, in `(0, 1e6]` (default 20).
    pub shininess: f64,
    /// Intensity added unshaded per channel, in `[0, MAX_INTENSITY]` (default 0).
    pub emissive: Rgb,
}

impl Default for Material {
    /// Reflectance 0.8, no specular, shininess 20, not emissive.
    fn default() -> Self {
        Self {
            reflectance: [0.8; 3],
            specular: 0.0,
            shininess: 20.0,
            emissive: [0.0; 3],
        }
    }
}

/// Coordinate space of a raw primitive (`space = "world"` (default) or `"screen"`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Space {
    /// World coordinates, projected by the camera.
    World,
    /// Screen coordinates: x, y in pixels (origin top-left, y down), z = screen depth in
    /// `[0, 1]` (0 = near); intensities given per vertex, unshaded.
    Screen,
}

/// One object of the scene (`[[object]]` with `kind = ...`).
#[derive(Clone, Debug, PartialEq, Serialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum Object {
    /// UV sphere: `tessellation` segments around the pole axis (world y) and
    /// `max(tessellation / 2, 2)` rings.
    Sphere {
        /// Centre.
        center: [f64; 3],
        /// Radius, in `[MIN_LENGTH, MAX_COORD]`.
        radius: f64,
        /// Segments around, `3..=1024` (default 32).
        tessellation: u32,
        /// Surface.
        material: Material,
    },
    /// Torus: `tessellation` segments around the axis, `max(tessellation / 2, 3)` around the
    /// tube.
    Torus {
        /// Centre.
        center: [f64; 3],
        /// Axis of revolution (normal of the torus plane); non-zero, normalised on load.
        axis: [f64; 3],
        /// Distance from the centre to the tube's centre line, > `minor_radius`.
        major_radius: f64,
        /// Tube radius, in `[MIN_LENGTH, MAX_COORD]`.
        minor_radius: f64,
        /// Segments around the axis, `3..=1024` (default 32).
        tessellation: u32,
        /// Surface.
        material: Material,
    },
    /// Right circular cone.
    Cone {
        /// Centre of the base disc.
        base: [f64; 3],
        /// From the base centre to the apex; its length is the height (non-zero).
        axis: [f64; 3],
        /// Base radius, in `[MIN_LENGTH, MAX_COORD]`.
        radius: f64,
        /// Segments around, `3..=1024` (default 32).
        tessellation: u32,
        /// Whether the base disc is drawn (default true). An uncapped cone is open: it is
        /// drawn two-sided, not back-face culled.
        capped: bool,
        /// Surface.
        material: Material,
    },
    /// Right circular cylinder.
    Cylinder {
        /// Centre of the bottom disc.
        base: [f64; 3],
        /// From the bottom centre to the top centre; its length is the height (non-zero).
        axis: [f64; 3],
        /// Radius, in `[MIN_LENGTH, MAX_COORD]`.
        radius: f64,
        /// Segments around, `3..=1024` (default 32).
        tessellation: u32,
        /// Whether both end discs are drawn (default true); an uncapped cylinder is drawn
        /// two-sided.
        capped: bool,
        /// Surface.
        material: Material,
    },
    /// A raw triangle, two-sided.
    Triangle {
        /// Coordinate space of the vertices.
        space: Space,
        /// The vertices.
        vertices: [[f64; 3]; 3],
        /// Per-vertex intensity (in `[0, MAX_INTENSITY]`), unshaded; required in screen space.
        /// `None`: shaded with `material` and the face normal turned towards the eye.
        intensity: Option<[Rgb; 3]>,
        /// Surface (used only when `intensity` is `None`).
        material: Material,
    },
    /// A raw quadrilateral, two-sided, split into triangles (0, 1, 2) and (0, 2, 3).
    Quad {
        /// Coordinate space of the vertices.
        space: Space,
        /// The vertices, in order around the quad.
        vertices: [[f64; 3]; 4],
        /// Per-vertex intensity (in `[0, MAX_INTENSITY]`); required in screen space.
        intensity: Option<[Rgb; 4]>,
        /// Surface (used only when `intensity` is `None`); each half is shaded with its own
        /// face normal.
        material: Material,
    },
    /// A line segment of constant intensity.
    Line {
        /// Coordinate space of the end points.
        space: Space,
        /// First end point.
        from: [f64; 3],
        /// Second end point.
        to: [f64; 3],
        /// Intensity per channel, in `[0, MAX_INTENSITY]`, unshaded.
        intensity: Rgb,
        /// Width in pixels, in `(0, 2 (diagonal + 2 MAX_GUARD_BAND)]` (default 1).
        width: f64,
    },
    /// A light point (a star, a runway light): a point of constant intensity.
    LightPoint {
        /// Coordinate space of the position.
        space: Space,
        /// Position.
        position: [f64; 3],
        /// Intensity per channel, in `[0, MAX_INTENSITY]`, unshaded.
        intensity: Rgb,
        /// Size in pixels, in `(0, 2 (diagonal + 2 MAX_GUARD_BAND)]` (default 1).
        size: f64,
    },
}

impl Scene {
    /// The embedded default scene (`src/scene/default.toml`): the layered-DoF paper's demo with
    /// a cone nearest, a sphere in the middle (in focus) and a torus farthest.
    pub fn default_scene() -> Scene {
        Self::embedded("default").expect("the embedded default scene is valid (tested)")
    }

    /// An embedded scene by name (see [`EMBEDDED`]); `None` if there is no such name.
    /// An embedded scene that fails validation also gives `None` (the tests rule that out).
    pub fn embedded(name: &str) -> Option<Scene> {
        if name == "default-pinhole" {
            // The default scene with a pinhole camera: everything in focus, no dof stage.
            let mut s = Self::default_scene();
            s.name = name.to_string();
            s.camera.lens = Lens::Pinhole;
            return Some(s);
        }
        let (n, text) = EMBEDDED.iter().find(|(n, _)| *n == name)?;
        let file = TomlFile::from_text(&format!("<embedded scene {n}>"), text);
        Self::from_toml(&file).ok()
    }

    /// Channels the scene renders: 3 (R, G, B) for a colour scene, else 1 (grey).
    pub fn channels(&self) -> usize {
        if self.image.colour { 3 } else { 1 }
    }

    /// Parses and validates a scene file. Every error names the line, the field and the
    /// allowed range.
    pub fn from_toml(file: &TomlFile) -> Result<Scene, FileError> {
        parse::scene_from_toml(file)
    }

    /// What a scene field expects, by dotted path (`object[2].tessellation` -> `an integer
    /// in 3..=1024`): the type and the allowed range that messages name. `None` for a path
    /// that is not a field.
    pub fn field_hint(path: &str) -> Option<String> {
        parse::hint(path)
    }

    /// An error at a scene field, found after parsing (a check against the hardware): at
    /// its file and line when the scene file gives the field, else naming the scene.
    pub fn error(&self, field: &str, msg: impl Into<String>) -> FileError {
        self.source.error(&self.name, field, msg)
    }

    /// Reads, parses and validates a scene file from disk.
    pub fn load(path: &str) -> Result<Scene, FileError> {
        Self::from_toml(&TomlFile::read(path)?)
    }
}

/// One projected vertex.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ScreenVertex {
    /// x in pixels (origin left).
    pub x: f64,
    /// y in pixels (origin top, y down).
    pub y: f64,
    /// Screen depth in `[0, 1]`, affine in screen space (0 = near, 1 = far).
    pub z: f64,
    /// Linear intensity per channel (1.0 = full white; may exceed 1, the pipeline
    /// saturates). A grey scene has three equal channels and renders channel 0 only.
    pub i: Rgb,
}

/// A screen-space primitive for the fixed-point pipeline.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Primitive {
    /// A Gouraud-shaded triangle (either winding).
    Triangle([ScreenVertex; 3]),
    /// A line segment.
    Line {
        /// First end point.
        a: ScreenVertex,
        /// Second end point.
        b: ScreenVertex,
        /// Width in pixels.
        width: f64,
    },
    /// A light point.
    Point {
        /// Centre and intensity.
        v: ScreenVertex,
        /// Size in pixels.
        size: f64,
    },
}

/// The screen region vertices may occupy after clipping, in pixels (screen coordinates,
/// so normally `x_min <= 0`, `x_max >= width`, likewise for y). It bounds the range of the
/// fixed-point vertex coordinates.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GuardBand {
    /// Left edge.
    pub x_min: f64,
    /// Right edge.
    pub x_max: f64,
    /// Top edge.
    pub y_min: f64,
    /// Bottom edge.
    pub y_max: f64,
}

impl GuardBand {
    /// The screen `[0, width] x [0, height]` widened by `margin` pixels on every side.
    pub fn around(width: u32, height: u32, margin: f64) -> Self {
        Self {
            x_min: -margin,
            x_max: f64::from(width) + margin,
            y_min: -margin,
            y_max: f64::from(height) + margin,
        }
    }

    /// Whether a point lies inside the band (edges included).
    pub fn contains(&self, x: f64, y: f64) -> bool {
        x >= self.x_min && x <= self.x_max && y >= self.y_min && y <= self.y_max
    }
}

/// Work counts of the host front end.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct FrontEndStats {
    /// Objects in the scene.
    pub objects: usize,
    /// Triangles before culling and clipping (tessellated + raw; a quad counts 2).
    pub triangles_in: usize,
    /// Back faces of closed canonical objects culled.
    pub culled_backfaces: usize,
    /// Triangles with at least one vertex in front of the near plane (clipped or dropped).
    pub clipped_near: usize,
    /// Triangles with at least one vertex beyond the far plane (clipped or dropped).
    pub clipped_far: usize,
    /// Triangles with at least one projected vertex outside the guard band.
    pub clipped_guard: usize,
    /// Triangles that left nothing after clipping (wholly behind near, beyond far or outside
    /// the guard band).
    pub dropped_outside: usize,
    /// Output triangles dropped for zero area (degenerate input or clipping slivers).
    pub dropped_degenerate: usize,
    /// Triangles emitted.
    pub triangles_out: usize,
    /// Lines emitted.
    pub lines: usize,
    /// Points emitted.
    pub points: usize,
    /// Vertices emitted (3 per triangle, 2 per line, 1 per point).
    pub vertices: usize,
}

impl FrontEndStats {
    /// Adds the counts of a part of the front end's work (`objects` and `vertices` are
    /// counted once over the whole scene, not per part).
    pub fn add(&mut self, o: &FrontEndStats) {
        self.triangles_in += o.triangles_in;
        self.culled_backfaces += o.culled_backfaces;
        self.clipped_near += o.clipped_near;
        self.clipped_far += o.clipped_far;
        self.clipped_guard += o.clipped_guard;
        self.dropped_outside += o.dropped_outside;
        self.dropped_degenerate += o.dropped_degenerate;
        self.triangles_out += o.triangles_out;
        self.lines += o.lines;
        self.points += o.points;
    }
}

/// The front end's output: screen-space primitives for the pipeline.
#[derive(Clone, Debug, PartialEq)]
pub struct HostScene {
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
    /// Background intensity per channel (at infinity, z = 1 beyond everything).
    pub background: Rgb,
    /// Channels the pipeline renders: 1 (grey, channel 0) or 3 (R, G, B).
    pub channels: usize,
    /// Primitives in deterministic order (object order, then tessellation order).
    pub prims: Vec<Primitive>,
    /// Work counts.
    pub stats: FrontEndStats,
}
