//! Camera, culling, clipping and projection: [`front_end`], and the same seen through one
//! point of a thin lens's aperture ([`front_end_through`]).

use super::shade::shade_vertex;
use super::tessellate::tessellate;
use std::sync::Arc;

mod mesh;
use super::vec3::{V3, add, cross, dot, lerp3, normalize, scale, sub};
use super::{
    Camera, FrontEndStats, GuardBand, HostScene, Material, MeshCache, Object, Primitive, Rgb,
    Scene, ScreenVertex, Space,
};

/// Screen depth of a view-space depth d (distance along the view axis):
/// `z = (1/near - 1/d) / (1/near - 1/far)`, 0 at near, 1 at far, affine in screen space.
pub fn screen_z(camera: &Camera, depth: f64) -> f64 {
    z_of(camera.near, camera.far, depth)
}

/// View-space depth of a screen depth z: the inverse of [`screen_z`],
/// `d = 1 / (1/near - z·(1/near - 1/far))`.
pub fn depth_from_screen_z(camera: &Camera, z: f64) -> f64 {
    d_of(camera.near, camera.far, z)
}

fn d_of(near: f64, far: f64, z: f64) -> f64 {
    1.0 / (1.0 / near - z * (1.0 / near - 1.0 / far))
}

fn z_of(near: f64, far: f64, d: f64) -> f64 {
    (1.0 / near - 1.0 / d) / (1.0 / near - 1.0 / far)
}

/// One point of a thin lens's aperture, for a physically based depth of field by
/// accumulation over the lens: the eye (camera position and look-at point together) moves by
/// `a` along the camera's right axis and `b` along its up axis, and the image is sheared so
/// that the plane at distance `focus` stays where the pinhole camera puts it. A point at
/// view depth `d` then moves by `f_px (a, -b) (1/focus - 1/d)` pixels (screen y points down;
/// `f_px = H / (2 tan(fov/2))`), zero on the focus plane. `jitter` then moves the whole
/// image by a sub-pixel offset (the truth's area sampling of each pixel).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LensPoint {
    /// Offset along the camera's right axis, scene units.
    pub a: f64,
    /// Offset along the camera's up axis, scene units.
    pub b: f64,
    /// Distance of the plane that stays fixed (the focus distance), scene units, > 0.
    pub focus: f64,
    /// A shift of the whole image, pixels `(x, y)` (0 for the lens alone).
    pub jitter: (f64, f64),
}

/// The look-at camera as a view transform plus a perspective projection to pixels.
#[derive(Clone)]
struct View {
    eye: V3,
    right: V3,
    up: V3,
    forward: V3,
    /// Pixels per unit of x/d or y/d.
    focal_px: f64,
    cx: f64,
    cy: f64,
    near: f64,
    far: f64,
    /// The lens point the view is seen through (`None`: the pinhole).
    lens: Option<LensPoint>,
}

impl View {
    fn new(camera: &Camera, width: u32, height: u32, lens: Option<LensPoint>) -> Self {
        let forward = normalize(sub(camera.look_at, camera.position));
        let right = normalize(cross(forward, camera.up));
        let up = cross(right, forward);
        let half = (camera.fov_y_deg.to_radians() * 0.5).tan();
        let focal_px = f64::from(height) * 0.5 / half;
        let (mut eye, mut cx, mut cy) = (
            camera.position,
            f64::from(width) * 0.5,
            f64::from(height) * 0.5,
        );
        if let Some(l) = lens {
            // The shear keeps the focus plane fixed: a point there moves by -f a / U with
            // the eye (x) and back by +f a / U here; likewise for y, which points down.
            eye = add(add(eye, scale(right, l.a)), scale(up, l.b));
            cx += focal_px * l.a / l.focus + l.jitter.0;
            cy -= focal_px * l.b / l.focus - l.jitter.1;
        }
        Self {
            eye,
            right,
            up,
            forward,
            focal_px,
            cx,
            cy,
            near: camera.near,
            far: camera.far,
            lens,
        }
    }

    /// A screen-space vertex (x, y in pixels, z screen depth) as seen through the lens
    /// point: moved by the parallax of its depth, `f_px (a, -b) (1/focus - 1/d)`.
    fn screen_vertex(&self, p: V3, i: Rgb) -> ScreenVertex {
        let mut v = sv(p, i);
        if let Some(l) = self.lens {
            let k = self.focal_px * (1.0 / l.focus - 1.0 / d_of(self.near, self.far, v.z));
            v.x += k * l.a + l.jitter.0;
            v.y += l.jitter.1 - k * l.b;
        }
        v
    }

    /// World -> view space `(x right, y up, d forward)`.
    fn to_view(&self, p: V3) -> V3 {
        let d = sub(p, self.eye);
        [dot(d, self.right), dot(d, self.up), dot(d, self.forward)]
    }

    /// View space (d >= near) -> screen.
    fn project(&self, v: V3, i: Rgb) -> ScreenVertex {
        let inv = 1.0 / v[2];
        ScreenVertex {
            x: self.cx + self.focal_px * v[0] * inv,
            y: self.cy - self.focal_px * v[1] * inv,
            z: z_of(self.near, self.far, v[2]).clamp(0.0, 1.0),
            i,
        }
    }
}

/// A view-space vertex with its intensity.
#[derive(Clone, Copy)]
struct Vv {
    p: V3,
    i: Rgb,
}

/// Sutherland–Hodgman against `d >= bound` (`keep_far`) or `d <= bound`, in view space.
fn clip_depth(poly: &[Vv], bound: f64, keep_far: bool) -> Vec<Vv> {
    let dist = |v: &Vv| {
        if keep_far {
            v.p[2] - bound
        } else {
            bound - v.p[2]
        }
    };
    let mut out = Vec::with_capacity(poly.len() + 1);
    for k in 0..poly.len() {
        let (a, b) = (poly[k], poly[(k + 1) % poly.len()]);
        let (da, db) = (dist(&a), dist(&b));
        if da >= 0.0 {
            out.push(a);
        }
        if (da >= 0.0) != (db >= 0.0) {
            let t = da / (da - db);
            let mut p = lerp3(a.p, b.p, t);
            p[2] = bound;
            out.push(Vv {
                p,
                i: lerp3(a.i, b.i, t),
            });
        }
    }
    out
}

fn lerp(a: &ScreenVertex, b: &ScreenVertex, t: f64) -> ScreenVertex {
    ScreenVertex {
        x: a.x + t * (b.x - a.x),
        y: a.y + t * (b.y - a.y),
        z: a.z + t * (b.z - a.z),
        i: lerp3(a.i, b.i, t),
    }
}

/// Sutherland–Hodgman against one guard-band edge: keep `coord(v) * sign >= bound * sign`.
fn clip_edge(
    poly: &[ScreenVertex],
    x_axis: bool,
    bound: f64,
    keep_greater: bool,
) -> Vec<ScreenVertex> {
    let coord = |v: &ScreenVertex| if x_axis { v.x } else { v.y };
    let dist = |v: &ScreenVertex| {
        if keep_greater {
            coord(v) - bound
        } else {
            bound - coord(v)
        }
    };
    let mut out = Vec::with_capacity(poly.len() + 1);
    for k in 0..poly.len() {
        let (a, b) = (&poly[k], &poly[(k + 1) % poly.len()]);
        let (da, db) = (dist(a), dist(b));
        if da >= 0.0 {
            out.push(*a);
        }
        if (da >= 0.0) != (db >= 0.0) {
            let mut v = lerp(a, b, da / (da - db));
            if x_axis {
                v.x = bound;
            } else {
                v.y = bound;
            }
            out.push(v);
        }
    }
    out
}

/// Twice the signed area.
fn area2(a: &ScreenVertex, b: &ScreenVertex, c: &ScreenVertex) -> f64 {
    (b.x - a.x) * (c.y - a.y) - (c.x - a.x) * (b.y - a.y)
}

/// Triangles whose doubled area is at most this (px²) are dropped as degenerate.
const MIN_AREA2: f64 = 1e-12;

struct Out<'a> {
    view: View,
    guard: &'a GuardBand,
    prims: Vec<Primitive>,
    stats: FrontEndStats,
}

impl Out<'_> {
    /// Clips a screen-space polygon to the guard band and emits it as a triangle fan.
    fn screen_polygon(&mut self, poly: Vec<ScreenVertex>) {
        let g = *self.guard;
        if poly.iter().any(|v| !g.contains(v.x, v.y)) {
            self.stats.clipped_guard += 1;
            let mut p = poly;
            for (x_axis, bound, keep_greater) in [
                (true, g.x_min, true),
                (true, g.x_max, false),
                (false, g.y_min, true),
                (false, g.y_max, false),
            ] {
                if p.is_empty() {
                    break;
                }
                p = clip_edge(&p, x_axis, bound, keep_greater);
            }
            self.fan(&p);
        } else {
            self.fan(&poly);
        }
    }

    fn fan(&mut self, p: &[ScreenVertex]) {
        if p.len() < 3 {
            self.stats.dropped_outside += 1;
            return;
        }
        for k in 1..p.len() - 1 {
            let mut t = [p[0], p[k], p[k + 1]];
            if area2(&t[0], &t[1], &t[2]).abs() <= MIN_AREA2 {
                self.stats.dropped_degenerate += 1;
                continue;
            }
            for v in &mut t {
                v.z = v.z.clamp(0.0, 1.0);
            }
            self.prims.push(Primitive::Triangle(t));
            self.stats.triangles_out += 1;
        }
    }

    /// A world-space triangle (already shaded and culled): near/far clip, project, guard clip.
    fn world_triangle(&mut self, p: [V3; 3], i: [Rgb; 3]) {
        let poly: Vec<Vv> = (0..3)
            .map(|k| Vv {
                p: self.view.to_view(p[k]),
                i: i[k],
            })
            .collect();
        let (near, far) = (self.view.near, self.view.far);
        let mut poly = poly;
        if poly.iter().any(|v| v.p[2] < near) {
            self.stats.clipped_near += 1;
            poly = clip_depth(&poly, near, true);
        }
        if poly.iter().any(|v| v.p[2] > far) {
            self.stats.clipped_far += 1;
            poly = clip_depth(&poly, far, false);
        }
        if poly.len() < 3 {
            self.stats.dropped_outside += 1;
            return;
        }
        let screen = poly.iter().map(|v| self.view.project(v.p, v.i)).collect();
        self.screen_polygon(screen);
    }

    fn line(&mut self, space: Space, from: V3, to: V3, intensity: Rgb, width: f64) {
        let (a, b) = match space {
            Space::Screen => (
                self.view.screen_vertex(from, intensity),
                self.view.screen_vertex(to, intensity),
            ),
            Space::World => {
                let (mut a, mut b) = (self.view.to_view(from), self.view.to_view(to));
                let (near, far) = (self.view.near, self.view.far);
                for (bound, keep_far) in [(near, true), (far, false)] {
                    let dist = |p: &V3| if keep_far { p[2] - bound } else { bound - p[2] };
                    let (da, db) = (dist(&a), dist(&b));
                    if da < 0.0 && db < 0.0 {
                        return;
                    }
                    if da < 0.0 || db < 0.0 {
                        let t = da / (da - db);
                        let mut p = lerp3(a, b, t);
                        p[2] = bound;
                        if da < 0.0 { a = p } else { b = p }
                    }
                }
                (
                    self.view.project(a, intensity),
                    self.view.project(b, intensity),
                )
            }
        };
        // Liang–Barsky against the guard band.
        let g = self.guard;
        let (dx, dy) = (b.x - a.x, b.y - a.y);
        let (mut t0, mut t1) = (0.0f64, 1.0f64);
        for (p, q) in [
            (-dx, a.x - g.x_min),
            (dx, g.x_max - a.x),
            (-dy, a.y - g.y_min),
            (dy, g.y_max - a.y),
        ] {
            if p == 0.0 {
                if q < 0.0 {
                    return;
                }
            } else {
                let r = q / p;
                if p < 0.0 {
                    t0 = t0.max(r);
                } else {
                    t1 = t1.min(r);
                }
            }
        }
        if t0 > t1 {
            return;
        }
        // A clipped end point lies on the band's edge up to rounding: snap it inside.
        let snap = |mut v: ScreenVertex| {
            v.x = v.x.clamp(g.x_min, g.x_max);
            v.y = v.y.clamp(g.y_min, g.y_max);
            v
        };
        let ca = if t0 > 0.0 { snap(lerp(&a, &b, t0)) } else { a };
        let cb = if t1 < 1.0 { snap(lerp(&a, &b, t1)) } else { b };
        self.prims.push(Primitive::Line {
            a: ca,
            b: cb,
            width,
        });
        self.stats.lines += 1;
    }

    fn point(&mut self, space: Space, position: V3, intensity: Rgb, size: f64) {
        let v = match space {
            Space::Screen => self.view.screen_vertex(position, intensity),
            Space::World => {
                let p = self.view.to_view(position);
                if !(p[2] >= self.view.near && p[2] <= self.view.far) {
                    return;
                }
                self.view.project(p, intensity)
            }
        };
        if self.guard.contains(v.x, v.y) && (0.0..=1.0).contains(&v.z) {
            self.prims.push(Primitive::Point { v, size });
            self.stats.points += 1;
        }
    }
}

fn sv(p: V3, i: Rgb) -> ScreenVertex {
    ScreenVertex {
        x: p[0],
        y: p[1],
        z: p[2],
        i,
    }
}

/// Whether a triangle faces the eye (counter-clockwise seen from it).
fn front_facing(p: [V3; 3], eye: V3) -> bool {
    dot(cross(sub(p[1], p[0]), sub(p[2], p[0])), sub(eye, p[0])) > 0.0
}

/// Runs the host front end: tessellate, cull, shade, clip (near and far in view space, then
/// the guard band in screen space) and project every object of the scene.
///
/// Triangles come out in object order, then tessellation order, each clipped polygon as a
/// fan from its first vertex; a triangle that needs no clipping keeps its vertex order.
/// Closed canonical objects are back-face culled; open ones (uncapped cones and cylinders)
/// and raw triangles and quads are two-sided and shaded with the normal facing the eye.
/// Lines are clipped to near, far and the guard band; light points are kept only when their
/// centre lies within near..far and inside the guard band.
pub fn front_end(scene: &Scene, guard: &GuardBand) -> HostScene {
    front_end_through(scene, guard, None)
}

/// [`front_end`] seen through one point of a thin lens's aperture ([`LensPoint`]; `None`:
/// the pinhole, exactly [`front_end`]): the eye moved on the lens, every world object
/// culled and shaded from the moved eye, projected and sheared so the focus plane stays
/// fixed, and screen-space objects moved by the parallax of their depth. The guard-band clip
/// comes after the shear, so every view is clipped in its own screen.
pub fn front_end_through(scene: &Scene, guard: &GuardBand, lens: Option<LensPoint>) -> HostScene {
    front_end_in(scene, guard, lens, (Vec::new(), &mut Vec::new()), None)
}

/// Triangles (and vertices) of a mesh per part of its emission on the threads (see
/// [`front_end_in`]): the default scene's sphere and torus (4096 triangles each) run in
/// four parts each.
const PART: usize = 1024;

/// [`front_end_through`] emitting the primitives into `prims` (cleared first: a list kept
/// from an earlier frame, so that a run of frames does not allocate it again).
///
/// A mesh of more than 1024 triangles is shaded and its triangles culled, projected and
/// clipped on the threads, in parts of 1024 triangles, each into its own list of
/// `parts` (kept by the caller across frames, like `prims`); the parts are then appended in
/// order. The primitives and counts are the serial ones whatever the threads: every
/// triangle is emitted alone, and the parts keep the tessellation order. With `meshes`,
/// an object tessellated in the frame before gets its mesh from there.
pub fn front_end_in(
    scene: &Scene,
    guard: &GuardBand,
    lens: Option<LensPoint>,
    lists: (Vec<Primitive>, &mut Vec<Vec<Primitive>>),
    meshes: Option<&MeshCache>,
) -> HostScene {
    front_end_parts(scene, guard, lens, lists, (PART, meshes))
}

/// [`front_end_in`] with parts of `part` triangles.
fn front_end_parts(
    scene: &Scene,
    guard: &GuardBand,
    lens: Option<LensPoint>,
    (mut prims, parts): (Vec<Primitive>, &mut Vec<Vec<Primitive>>),
    (part, meshes): (usize, Option<&MeshCache>),
) -> HostScene {
    prims.clear();
    let view = View::new(&scene.camera, scene.image.width, scene.image.height, lens);
    let eye = view.eye;
    let ambient = scene.shading.ambient;
    let lights = &scene.lights;
    let shade = |p: V3, n: V3, m: &Material| shade_vertex(p, n, eye, m, ambient, lights);
    let mut out = Out {
        view,
        guard,
        prims,
        stats: FrontEndStats::default(),
    };
    out.stats.objects = scene.objects.len();
    if let Some(m) = meshes {
        m.next_frame();
    }
    for object in &scene.objects {
        match object {
            Object::Sphere { material, .. }
            | Object::Torus { material, .. }
            | Object::Cone { material, .. }
            | Object::Cylinder { material, .. } => {
                let mesh = match meshes {
                    Some(m) => m.mesh(object),
                    None => tessellate(object).map(Arc::new),
                }
                .expect("canonical objects tessellate");
                mesh::emit(&mut out, &mesh, |p, n| shade(p, n, material), (parts, part));
            }
            Object::Triangle {
                space,
                vertices,
                intensity,
                material,
            } => {
                out.stats.triangles_in += 1;
                raw_triangle(&mut out, *space, *vertices, *intensity, material, &shade);
            }
            Object::Quad {
                space,
                vertices,
                intensity,
                material,
            } => {
                out.stats.triangles_in += 2;
                for [a, b, c] in [[0, 1, 2], [0, 2, 3]] {
                    let v = [vertices[a], vertices[b], vertices[c]];
                    let i = intensity.map(|i| [i[a], i[b], i[c]]);
                    raw_triangle(&mut out, *space, v, i, material, &shade);
                }
            }
            Object::Line {
                space,
                from,
                to,
                intensity,
                width,
            } => {
                out.line(*space, *from, *to, *intensity, *width);
            }
            Object::LightPoint {
                space,
                position,
                intensity,
                size,
            } => {
                out.point(*space, *position, *intensity, *size);
            }
        }
    }
    let s = &mut out.stats;
    s.vertices = 3 * s.triangles_out + 2 * s.lines + s.points;
    HostScene {
        width: scene.image.width,
        height: scene.image.height,
        background: scene.image.background,
        channels: scene.channels(),
        prims: out.prims,
        stats: out.stats,
    }
}

fn raw_triangle(
    out: &mut Out,
    space: Space,
    v: [V3; 3],
    intensity: Option<[Rgb; 3]>,
    material: &Material,
    shade: &dyn Fn(V3, V3, &Material) -> Rgb,
) {
    match space {
        Space::Screen => {
            let i = intensity.unwrap_or([[0.0; 3]; 3]);
            let poly = (0..3).map(|k| out.view.screen_vertex(v[k], i[k])).collect();
            out.screen_polygon(poly);
        }
        Space::World => {
            let i = intensity.unwrap_or_else(|| {
                let mut n = cross(sub(v[1], v[0]), sub(v[2], v[0]));
                if !front_facing(v, out.view.eye) {
                    n = scale(n, -1.0);
                }
                v.map(|p| shade(p, n, material))
            });
            out.world_triangle(v, i);
        }
    }
}
