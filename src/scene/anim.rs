//! Animated scenes: the `[sequence]` table of a scene file (docs/sequence.md). Keyframes move
//! the camera (position, look-at, up, the thin lens's focus distance) and objects
//! (translation, rotation, uniform scale about the object's anchor); [`Scene::frame`]
//! evaluates them at a frame and gives the still scene of that frame.
//!
//! Interpolation between keys is per component, in the key's index: `linear`, or `spline`
//! (a uniform Catmull-Rom spline through the keys, the end keys repeated as their outer
//! neighbours, so the path passes through every key and its velocity is continuous). Before
//! the first key a track holds the first key's value, after the last the last's.

use super::vec3::{add, cross, norm, sub};
use super::{Lens, Object, Scene, Space};
use crate::error::FileError;
use serde::Serialize;

/// How the keys of a track are joined.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Interpolation {
    /// Straight lines between keys.
    Linear,
    /// Uniform Catmull-Rom through the keys.
    Spline,
}

/// A camera key (`[[sequence.camera]]`): a field the key leaves out is the `[camera]` value.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct CameraKey {
    /// Frame of the key.
    pub frame: u32,
    /// Eye.
    pub position: [f64; 3],
    /// Point looked at.
    pub look_at: [f64; 3],
    /// Screen up.
    pub up: [f64; 3],
    /// The thin lens's focus distance (a focus pull); `None` with a pinhole.
    pub focus_distance: Option<f64>,
}

/// An object key (`[[sequence.object]]`): the object's pose relative to the scene file.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ObjectKey {
    /// Index of the object in `[[object]]`.
    pub object: usize,
    /// Frame of the key.
    pub frame: u32,
    /// Added to every point after rotation and scale (scene units; pixels and screen depth
    /// for a screen-space object).
    pub translate: [f64; 3],
    /// Rotation about the anchor, degrees about x, then y, then z.
    pub rotate_deg: [f64; 3],
    /// Uniform scale about the anchor.
    pub scale: f64,
}

/// The `[sequence]` of a scene.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Sequence {
    /// Frames, `0..frames`.
    pub frames: u32,
    /// Frame rate of the sequence, Hz (default the display's refresh): the period every
    /// frame must fit in.
    pub rate_hz: f64,
    /// How keys are joined.
    pub interpolation: Interpolation,
    /// Camera keys, by frame.
    pub camera: Vec<CameraKey>,
    /// Object keys, by object then frame.
    pub objects: Vec<ObjectKey>,
}

impl Sequence {
    /// Whether nothing moves: no key differs from the scene as written.
    pub fn is_still(&self, scene: &Scene) -> bool {
        let c = &scene.camera;
        let focus = match c.lens {
            Lens::ThinLens { focus_distance, .. } => Some(focus_distance),
            Lens::Pinhole => None,
        };
        self.camera.iter().all(|k| {
            k.position == c.position
                && k.look_at == c.look_at
                && k.up == c.up
                && k.focus_distance == focus
        }) && self
            .objects
            .iter()
            .all(|k| k.translate == [0.0; 3] && k.rotate_deg == [0.0; 3] && k.scale == 1.0)
    }

    /// The objects that move (have keys), in scene order.
    pub fn moving_objects(&self) -> Vec<usize> {
        let mut v: Vec<usize> = self.objects.iter().map(|k| k.object).collect();
        v.sort_unstable();
        v.dedup();
        v
    }
}

/// The value of a track of keys (`(frame, value)`, frames increasing) at frame `f`.
pub fn interpolate<const N: usize>(
    keys: &[(u32, [f64; N])],
    f: f64,
    how: Interpolation,
) -> [f64; N] {
    let (Some(first), Some(last)) = (keys.first(), keys.last()) else {
        return [0.0; N];
    };
    if f <= first.0 as f64 {
        return first.1;
    }
    if f >= last.0 as f64 {
        return last.1;
    }
    let i = keys.partition_point(|k| (k.0 as f64) <= f) - 1;
    let (f0, f1) = (keys[i].0 as f64, keys[i + 1].0 as f64);
    let t = (f - f0) / (f1 - f0);
    let p1 = keys[i].1;
    let p2 = keys[i + 1].1;
    match how {
        Interpolation::Linear => std::array::from_fn(|c| p1[c] + t * (p2[c] - p1[c])),
        Interpolation::Spline => {
            let p0 = keys[i.saturating_sub(1)].1;
            let p3 = keys[(i + 2).min(keys.len() - 1)].1;
            let (t2, t3) = (t * t, t * t * t);
            std::array::from_fn(|c| {
                0.5 * (2.0 * p1[c]
                    + (p2[c] - p0[c]) * t
                    + (2.0 * p0[c] - 5.0 * p1[c] + 4.0 * p2[c] - p3[c]) * t2
                    + (3.0 * p1[c] - p0[c] - 3.0 * p2[c] + p3[c]) * t3)
            })
        }
    }
}

/// `v` rotated by `deg` about x, then y, then z.
fn rotate(v: [f64; 3], deg: [f64; 3]) -> [f64; 3] {
    let [a, b, c] = deg.map(f64::to_radians);
    let [x, y, z] = v;
    let (y, z) = (y * a.cos() - z * a.sin(), y * a.sin() + z * a.cos());
    let (x, z) = (x * b.cos() + z * b.sin(), -x * b.sin() + z * b.cos());
    let (x, y) = (x * c.cos() - y * c.sin(), x * c.sin() + y * c.cos());
    [x, y, z]
}

/// A pose: `p -> anchor + R(s (p - anchor)) + t`.
struct Pose {
    translate: [f64; 3],
    rotate_deg: [f64; 3],
    scale: f64,
}

impl Pose {
    fn point(&self, anchor: [f64; 3], p: [f64; 3]) -> [f64; 3] {
        let d = sub(p, anchor).map(|c| c * self.scale);
        add(add(anchor, rotate(d, self.rotate_deg)), self.translate)
    }
    fn vector(&self, v: [f64; 3]) -> [f64; 3] {
        rotate(v.map(|c| c * self.scale), self.rotate_deg)
    }
}

fn centroid<const N: usize>(v: &[[f64; 3]; N]) -> [f64; 3] {
    std::array::from_fn(|c| v.iter().map(|p| p[c]).sum::<f64>() / N as f64)
}

/// `o` moved by `pose` (anchors: centre, base, the vertices' centroid, the line's midpoint,
/// the point). A screen-space object only translates (the keys are checked on load).
fn moved(o: &Object, pose: &Pose) -> Object {
    let mut o = o.clone();
    match &mut o {
        Object::Sphere { center, radius, .. } => {
            *center = add(*center, pose.translate);
            *radius *= pose.scale;
        }
        Object::Torus {
            center,
            axis,
            major_radius,
            minor_radius,
            ..
        } => {
            *center = add(*center, pose.translate);
            *axis = rotate(*axis, pose.rotate_deg);
            *major_radius *= pose.scale;
            *minor_radius *= pose.scale;
        }
        Object::Cone {
            base, axis, radius, ..
        }
        | Object::Cylinder {
            base, axis, radius, ..
        } => {
            *base = add(*base, pose.translate);
            *axis = pose.vector(*axis);
            *radius *= pose.scale;
        }
        Object::Triangle { vertices, .. } => {
            let a = centroid(vertices);
            *vertices = vertices.map(|p| pose.point(a, p));
        }
        Object::Quad { vertices, .. } => {
            let a = centroid(vertices);
            *vertices = vertices.map(|p| pose.point(a, p));
        }
        Object::Line { from, to, .. } => {
            let a = centroid(&[*from, *to]);
            *from = pose.point(a, *from);
            *to = pose.point(a, *to);
        }
        Object::LightPoint { position, .. } => *position = add(*position, pose.translate),
    }
    o
}

/// The coordinate space of an object (canonical objects are in world space).
pub fn space_of(o: &Object) -> Space {
    match o {
        Object::Triangle { space, .. }
        | Object::Quad { space, .. }
        | Object::Line { space, .. }
        | Object::LightPoint { space, .. } => *space,
        _ => Space::World,
    }
}

impl Scene {
    /// The still scene of frame `f` of the scene's `[sequence]` (the scene itself when it has
    /// none). An interpolated camera whose up is parallel to its view, or a focus pull that
    /// passes the focal length, is refused naming the frame.
    pub fn frame(&self, f: u32) -> Result<Scene, FileError> {
        let Some(seq) = &self.sequence else {
            return Ok(self.clone());
        };
        let mut s = self.clone();
        s.sequence = None;
        let ff = f as f64;
        let how = seq.interpolation;
        if !seq.camera.is_empty() {
            let track = |g: fn(&CameraKey) -> [f64; 3]| -> Vec<(u32, [f64; 3])> {
                seq.camera.iter().map(|k| (k.frame, g(k))).collect()
            };
            s.camera.position = interpolate(&track(|k| k.position), ff, how);
            s.camera.look_at = interpolate(&track(|k| k.look_at), ff, how);
            s.camera.up = interpolate(&track(|k| k.up), ff, how);
            let view = sub(s.camera.look_at, s.camera.position);
            let upright = norm(cross(view, s.camera.up)) > 1e-12 * norm(view) * norm(s.camera.up);
            if !upright {
                return Err(self.error(
                    "sequence.camera",
                    format!(
                        "at frame {f} the interpolated camera's up {:?} is parallel to its view direction {view:?} (or zero): add a key or change up",
                        s.camera.up
                    ),
                ));
            }
            if let Lens::ThinLens {
                focus_distance,
                focal_length,
                ..
            } = &mut s.camera.lens
            {
                let keys: Vec<(u32, [f64; 1])> = seq
                    .camera
                    .iter()
                    .filter_map(|k| Some((k.frame, [k.focus_distance?])))
                    .collect();
                if !keys.is_empty() {
                    let [d] = interpolate(&keys, ff, how);
                    let beyond = d > *focal_length;
                    if !beyond {
                        return Err(self.error(
                            "sequence.camera",
                            format!(
                                "at frame {f} the interpolated focus_distance {d} is not above the focal length {focal_length}: the spline overshoots between keys; use interpolation = \"linear\" or add a key"
                            ),
                        ));
                    }
                    *focus_distance = d;
                }
            }
        }
        for o in seq.moving_objects() {
            let track = |g: fn(&ObjectKey) -> [f64; 3]| -> Vec<(u32, [f64; 3])> {
                seq.objects
                    .iter()
                    .filter(|k| k.object == o)
                    .map(|k| (k.frame, g(k)))
                    .collect()
            };
            let [scale] = interpolate(
                &seq.objects
                    .iter()
                    .filter(|k| k.object == o)
                    .map(|k| (k.frame, [k.scale]))
                    .collect::<Vec<_>>(),
                ff,
                how,
            );
            let pose = Pose {
                translate: interpolate(&track(|k| k.translate), ff, how),
                rotate_deg: interpolate(&track(|k| k.rotate_deg), ff, how),
                scale,
            };
            let positive = scale > 0.0;
            if !positive {
                return Err(self.error(
                    &format!("sequence.object (object {o})"),
                    format!("at frame {f} the interpolated scale {scale} is not positive: the spline overshoots between keys; use interpolation = \"linear\""),
                ));
            }
            s.objects[o] = moved(&self.objects[o], &pose);
        }
        Ok(s)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn linear_and_spline_pass_through_the_keys_and_hold_at_the_ends() {
        let keys = [(0, [0.0]), (10, [10.0]), (20, [0.0])];
        for how in [Interpolation::Linear, Interpolation::Spline] {
            for (f, v) in [
                (0.0, 0.0),
                (10.0, 10.0),
                (20.0, 0.0),
                (-5.0, 0.0),
                (30.0, 0.0),
            ] {
                assert_eq!(interpolate(&keys, f, how), [v], "{how:?} at {f}");
            }
        }
        assert_eq!(interpolate(&keys, 5.0, Interpolation::Linear), [5.0]);
        // The spline rounds the peak: above the line before it.
        assert!(interpolate(&keys, 5.0, Interpolation::Spline)[0] > 5.0);
        // Between inner keys of a straight, evenly keyed track the spline is the line (the
        // end segments ease in and out: their outer neighbour is the end key repeated).
        let line = [(0, [0.0]), (4, [4.0]), (8, [8.0]), (12, [12.0])];
        assert!((interpolate(&line, 6.5, Interpolation::Spline)[0] - 6.5).abs() < 1e-12);
    }

    #[test]
    fn rotation_is_x_then_y_then_z() {
        let r = rotate([1.0, 0.0, 0.0], [0.0, 0.0, 90.0]);
        assert!((r[0]).abs() < 1e-12 && (r[1] - 1.0).abs() < 1e-12);
        let r = rotate([0.0, 1.0, 0.0], [90.0, 0.0, 0.0]);
        assert!((r[2] - 1.0).abs() < 1e-12);
    }
}
