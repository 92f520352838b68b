//! `[sequence]`, `[[sequence.camera]]` and `[[sequence.object]]` of a scene file
//! (docs/sequence.md): the frame count and rate, the interpolation and the keys.

use super::schema::{COORD, REFRESH, Range, Vec3};
use super::{Ctx, R};
use crate::scene::anim::{CameraKey, Interpolation, ObjectKey, Sequence, space_of};
use crate::scene::{Camera, Lens, Object, Space};
use serde::Deserialize;

/// Most frames of a sequence.
pub const MAX_FRAMES: u32 = 1_000_000;
/// A key's scale.
const SCALE: Range = Range::Closed(1e-6, 1e6);
/// A key's rotation, degrees.
const DEGREES: Range = Range::Closed(-1e6, 1e6);

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RawSequence {
    frames: i64,
    rate_hz: Option<f64>,
    interpolation: Option<String>,
    #[serde(default)]
    camera: Vec<RawCameraKey>,
    #[serde(default)]
    object: Vec<RawObjectKey>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawCameraKey {
    frame: i64,
    position: Option<Vec3>,
    look_at: Option<Vec3>,
    up: Option<Vec3>,
    focus_distance: Option<f64>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawObjectKey {
    object: i64,
    frame: i64,
    translate: Option<Vec3>,
    rotate_deg: Option<Vec3>,
    scale: Option<f64>,
}

/// Frames of a track must increase: the error names the key and the frame before it.
fn increasing(c: &Ctx, path: &str, prev: Option<u32>, f: u32) -> R<()> {
    match prev {
        Some(p) if f <= p => Err(c.err(
            &format!("{path}.frame"),
            format!(
                "must be greater than the previous key's frame {p} (keys in frame order), got {f}"
            ),
        )),
        _ => Ok(()),
    }
}

/// The validated `[sequence]` of a scene with `camera`, `objects` and a display refreshed
/// at `refresh_hz`.
pub(super) fn sequence(
    c: &Ctx,
    raw: &RawSequence,
    camera: &Camera,
    objects: &[Object],
    refresh_hz: f64,
) -> R<Sequence> {
    let frames = c.int("sequence.frames", raw.frames, 1, MAX_FRAMES)?;
    let rate_hz = c.opt("sequence.rate_hz", raw.rate_hz, refresh_hz, REFRESH)?;
    let interpolation = match raw.interpolation.as_deref() {
        None | Some("linear") => Interpolation::Linear,
        Some("spline") => Interpolation::Spline,
        Some(x) => {
            return Err(c.err(
                "sequence.interpolation",
                format!("must be \"linear\" or \"spline\", got \"{x}\""),
            ));
        }
    };
    let last = frames - 1;
    let mut cam = Vec::with_capacity(raw.camera.len());
    for (k, key) in raw.camera.iter().enumerate() {
        let p = format!("sequence.camera[{k}]");
        let frame = c.int(&format!("{p}.frame"), key.frame, 0, last)?;
        increasing(c, &p, cam.last().map(|k: &CameraKey| k.frame), frame)?;
        let v = |name: &str, x: &Option<Vec3>, base: [f64; 3]| -> R<[f64; 3]> {
            match x {
                Some(v) => c.vec3(&format!("{p}.{name}"), Vec3(v.0)),
                None => Ok(base),
            }
        };
        let focus_distance = match (&camera.lens, key.focus_distance) {
            (Lens::Pinhole, Some(_)) => {
                return Err(c.err(
                    &format!("{p}.focus_distance"),
                    "needs a thin lens ([camera.lens] kind = \"thin_lens\"); a pinhole camera has no focus",
                ));
            }
            (Lens::Pinhole, None) => None,
            (Lens::ThinLens { focal_length, .. }, Some(d)) => {
                let path = format!("{p}.focus_distance");
                let d = c.num(&path, d, COORD)?;
                let beyond = d > *focal_length;
                if !beyond {
                    return Err(c.err(
                        &path,
                        format!("must be greater than the focal length {focal_length}, got {d}"),
                    ));
                }
                Some(d)
            }
            (Lens::ThinLens { focus_distance, .. }, None) => Some(*focus_distance),
        };
        cam.push(CameraKey {
            frame,
            position: v("position", &key.position, camera.position)?,
            look_at: v("look_at", &key.look_at, camera.look_at)?,
            up: v("up", &key.up, camera.up)?,
            focus_distance,
        });
    }
    let mut obj: Vec<ObjectKey> = Vec::with_capacity(raw.object.len());
    for (k, key) in raw.object.iter().enumerate() {
        let p = format!("sequence.object[{k}]");
        let n = objects.len() as u32;
        if n == 0 {
            return Err(c.err(
                &format!("{p}.object"),
                "the scene has no [[object]] to move",
            ));
        }
        let object = c.int(&format!("{p}.object"), key.object, 0, n - 1)? as usize;
        let frame = c.int(&format!("{p}.frame"), key.frame, 0, last)?;
        let prev = obj
            .iter()
            .rev()
            .find(|k| k.object == object)
            .map(|k| k.frame);
        increasing(c, &p, prev, frame)?;
        let translate = match &key.translate {
            Some(v) => c.vec3(&format!("{p}.translate"), Vec3(v.0))?,
            None => [0.0; 3],
        };
        let rotate_deg = match &key.rotate_deg {
            Some(v) => {
                for (j, x) in v.0.iter().enumerate() {
                    c.num(&format!("{p}.rotate_deg[{j}]"), *x, DEGREES)?;
                }
                v.0
            }
            None => [0.0; 3],
        };
        let scale = c.opt(&format!("{p}.scale"), key.scale, 1.0, SCALE)?;
        if space_of(&objects[object]) == Space::Screen && (rotate_deg != [0.0; 3] || scale != 1.0) {
            return Err(c.err(
                &p,
                format!(
                    "object {object} is in screen space: its keys may only translate (pixels and screen depth), not rotate_deg or scale"
                ),
            ));
        }
        obj.push(ObjectKey {
            object,
            frame,
            translate,
            rotate_deg,
            scale,
        });
    }
    Ok(Sequence {
        frames,
        rate_hz,
        interpolation,
        camera: cam,
        objects: obj,
    })
}
