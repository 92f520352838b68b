//! A canonical object's mesh through the host front end: its vertices shaded, its
//! triangles culled, projected and clipped, on the threads in parts for a large mesh.

use super::{Out, front_facing};
use crate::scene::tessellate::Mesh;
use crate::scene::vec3::{V3, scale};
use crate::scene::{FrontEndStats, Primitive, Rgb};
use rayon::prelude::*;

/// Emits `mesh` into `out`, a vertex shaded by `shade(position, normal)`. A mesh of more
/// than `part` triangles runs on the threads in parts of `part` triangles, each into its
/// own list of `parts`, appended in order (see [`super::front_end_in`]).
pub(super) fn emit(
    out: &mut Out,
    mesh: &Mesh,
    shade: impl Fn(V3, V3) -> Rgb + Sync,
    (parts, part): (&mut Vec<Vec<Primitive>>, usize),
) {
    let eye = out.view.eye;
    out.stats.triangles_in += mesh.triangles.len();
    // `scale(n, 1.0)` is `n` exactly.
    let shaded = |flip: f64| -> Vec<Rgb> {
        mesh.positions
            .par_iter()
            .zip(&mesh.normals)
            .with_min_len(part)
            .map(|(p, n)| shade(*p, scale(*n, flip)))
            .collect()
    };
    let front = shaded(1.0);
    let back = if mesh.closed {
        Vec::new()
    } else {
        shaded(-1.0)
    };
    let emit_tris = |o: &mut Out, tris: &[[u32; 3]]| {
        for t in tris {
            let idx = t.map(|k| k as usize);
            let p = idx.map(|k| mesh.positions[k]);
            let facing = front_facing(p, eye);
            if mesh.closed && !facing {
                o.stats.culled_backfaces += 1;
                continue;
            }
            let i = if facing {
                idx.map(|k| front[k])
            } else {
                idx.map(|k| back[k])
            };
            o.world_triangle(p, i);
        }
    };
    let n = mesh.triangles.len().div_ceil(part);
    if n <= 1 {
        emit_tris(out, &mesh.triangles);
        return;
    }
    if parts.len() < n {
        parts.resize_with(n, Vec::new);
    }
    let (view, guard) = (&out.view, out.guard);
    let counts: Vec<FrontEndStats> = parts[..n]
        .par_iter_mut()
        .zip(mesh.triangles.par_chunks(part))
        .map(|(list, tris)| {
            list.clear();
            let mut o = Out {
                view: view.clone(),
                guard,
                prims: std::mem::take(list),
                stats: FrontEndStats::default(),
            };
            emit_tris(&mut o, tris);
            *list = o.prims;
            o.stats
        })
        .collect();
    for (list, c) in parts.iter().zip(&counts) {
        out.prims.extend_from_slice(list);
        out.stats.add(c);
    }
}

#[cfg(test)]
mod tests {
    use super::super::front_end_parts;
    use crate::scene::{GuardBand, LensPoint, MeshCache, Scene};

    /// Meshes emitted in parts on the threads give the serial primitives and counts: the
    /// default scene's meshes in parts of 7 triangles against one part per mesh, through
    /// the pinhole and a lens point, with a guard band that clips, and again on the part
    /// lists and the meshes the first run left (a second frame).
    #[test]
    fn parts_give_the_serial_emission() {
        let scene = Scene::embedded("default").expect("embedded scene");
        let guard = GuardBand {
            x_min: 200.0,
            x_max: 440.0,
            y_min: 150.0,
            y_max: 330.0,
        };
        let lens = LensPoint {
            a: 0.03,
            b: -0.02,
            focus: 6.0,
            jitter: (0.25, -0.5),
        };
        let mut parts = vec![Vec::new(); 2];
        let cache = MeshCache::new();
        for lens in [None, Some(lens)] {
            let serial = front_end_parts(
                &scene,
                &guard,
                lens,
                (Vec::new(), &mut Vec::new()),
                (usize::MAX, None),
            );
            assert!(serial.stats.clipped_guard > 0 && serial.stats.culled_backfaces > 0);
            for _ in 0..2 {
                let split = front_end_parts(
                    &scene,
                    &guard,
                    lens,
                    (Vec::new(), &mut parts),
                    (7, Some(&cache)),
                );
                assert!(parts.len() > 500, "{} parts", parts.len());
                assert_eq!(split, serial);
            }
        }
    }
}
