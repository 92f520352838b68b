//! Tessellation of the canonical objects into indexed triangle meshes with per-vertex
//! normals (smooth shading) and counter-clockwise winding seen from outside.

use super::Object;
use super::vec3::{V3, add, basis, cross, dot, normalize, scale, sub};
use std::f64::consts::TAU;

/// An indexed triangle mesh in world space.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Mesh {
    /// Vertex positions.
    pub positions: Vec<[f64; 3]>,
    /// Unit vertex normals, pointing outwards.
    pub normals: Vec<[f64; 3]>,
    /// Triangles as vertex indices, counter-clockwise seen from the side the normals point to.
    pub triangles: Vec<[u32; 3]>,
    /// Whether the surface is closed (its back faces are never visible and may be culled).
    pub closed: bool,
}

impl Mesh {
    fn vertex(&mut self, p: V3, n: V3) -> u32 {
        self.positions.push(p);
        self.normals.push(normalize(n));
        (self.positions.len() - 1) as u32
    }

    /// Adds a triangle, ordered so that its face normal agrees with its vertex normals.
    fn tri(&mut self, a: u32, b: u32, c: u32) {
        let p = |k: u32| self.positions[k as usize];
        let n = |k: u32| self.normals[k as usize];
        let face = cross(sub(p(b), p(a)), sub(p(c), p(a)));
        let avg = add(add(n(a), n(b)), n(c));
        if dot(face, avg) < 0.0 {
            self.triangles.push([a, c, b]);
        } else {
            self.triangles.push([a, b, c]);
        }
    }

    fn quad(&mut self, a: u32, b: u32, c: u32, d: u32) {
        self.tri(a, b, c);
        self.tri(a, c, d);
    }
}

/// Tessellates a canonical object (sphere, torus, cone, cylinder); `None` for raw primitives.
///
/// * Sphere: pole axis world y, `n = tessellation` segments around, `max(n/2, 2)` rings:
///   `2n·(rings - 1)` triangles.
/// * Torus: `n` segments around the axis, `max(n/2, 3)` around the tube, two triangles each.
/// * Cone: `n` side triangles, each with its own apex vertex whose normal is the side normal at
///   the segment's middle angle; plus `n` cap triangles if capped.
/// * Cylinder: `2n` side triangles, plus `n` per cap if capped.
///
/// Cap vertices carry the cap normal. Uncapped cones and cylinders are open (`closed = false`).
pub fn tessellate(object: &Object) -> Option<Mesh> {
    let mut m = Mesh::default();
    match *object {
        Object::Sphere {
            center,
            radius,
            tessellation,
            ..
        } => {
            let n = tessellation;
            let rings = (n / 2).max(2);
            m.closed = true;
            let dir = |theta: f64, phi: f64| {
                [
                    theta.sin() * phi.cos(),
                    theta.cos(),
                    -theta.sin() * phi.sin(),
                ]
            };
            let north = m.vertex(add(center, [0.0, radius, 0.0]), [0.0, 1.0, 0.0]);
            let first = north + 1;
            for k in 1..rings {
                let theta = std::f64::consts::PI * f64::from(k) / f64::from(rings);
                for j in 0..n {
                    let d = dir(theta, TAU * f64::from(j) / f64::from(n));
                    m.vertex(add(center, scale(d, radius)), d);
                }
            }
            let south = m.vertex(add(center, [0.0, -radius, 0.0]), [0.0, -1.0, 0.0]);
            let at = |k: u32, j: u32| first + (k - 1) * n + j % n;
            for j in 0..n {
                m.tri(north, at(1, j), at(1, j + 1));
            }
            for k in 1..rings - 1 {
                for j in 0..n {
                    m.quad(at(k, j), at(k + 1, j), at(k + 1, j + 1), at(k, j + 1));
                }
            }
            for j in 0..n {
                m.tri(south, at(rings - 1, j + 1), at(rings - 1, j));
            }
        }
        Object::Torus {
            center,
            axis,
            major_radius,
            minor_radius,
            tessellation,
            ..
        } => {
            let n = tessellation;
            let t = (n / 2).max(3);
            m.closed = true;
            let a = normalize(axis);
            let (u, v) = basis(a);
            for i in 0..n {
                let th = TAU * f64::from(i) / f64::from(n);
                let radial = add(scale(u, th.cos()), scale(v, th.sin()));
                for j in 0..t {
                    let ph = TAU * f64::from(j) / f64::from(t);
                    let normal = add(scale(radial, ph.cos()), scale(a, ph.sin()));
                    let p = add(
                        add(center, scale(radial, major_radius)),
                        scale(normal, minor_radius),
                    );
                    m.vertex(p, normal);
                }
            }
            let at = |i: u32, j: u32| (i % n) * t + j % t;
            for i in 0..n {
                for j in 0..t {
                    m.quad(at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1));
                }
            }
        }
        Object::Cone {
            base,
            axis,
            radius,
            tessellation,
            capped,
            ..
        } => {
            let n = tessellation;
            m.closed = capped;
            let h = dot(axis, axis).sqrt();
            let a = scale(axis, 1.0 / h);
            let (u, v) = basis(a);
            let radial = |ang: f64| add(scale(u, ang.cos()), scale(v, ang.sin()));
            let side_normal = |ang: f64| add(scale(radial(ang), h), scale(a, radius));
            let apex = add(base, axis);
            let ang = |j: u32| TAU * f64::from(j) / f64::from(n);
            let ring0 = m.positions.len() as u32;
            for j in 0..n {
                m.vertex(
                    add(base, scale(radial(ang(j)), radius)),
                    side_normal(ang(j)),
                );
            }
            for j in 0..n {
                let mid = TAU * (f64::from(j) + 0.5) / f64::from(n);
                let tip = m.vertex(apex, side_normal(mid));
                m.tri(ring0 + j, ring0 + (j + 1) % n, tip);
            }
            if capped {
                disc(&mut m, base, scale(a, -1.0), radius, n, &radial);
            }
        }
        Object::Cylinder {
            base,
            axis,
            radius,
            tessellation,
            capped,
            ..
        } => {
            let n = tessellation;
            m.closed = capped;
            let a = normalize(axis);
            let (u, v) = basis(a);
            let radial = |ang: f64| add(scale(u, ang.cos()), scale(v, ang.sin()));
            let ang = |j: u32| TAU * f64::from(j) / f64::from(n);
            let bottom = m.positions.len() as u32;
            for j in 0..n {
                m.vertex(add(base, scale(radial(ang(j)), radius)), radial(ang(j)));
            }
            let top = m.positions.len() as u32;
            for j in 0..n {
                m.vertex(
                    add(add(base, axis), scale(radial(ang(j)), radius)),
                    radial(ang(j)),
                );
            }
            for j in 0..n {
                let k = (j + 1) % n;
                m.quad(bottom + j, bottom + k, top + k, top + j);
            }
            if capped {
                disc(&mut m, base, scale(a, -1.0), radius, n, &radial);
                disc(&mut m, add(base, axis), a, radius, n, &radial);
            }
        }
        _ => return None,
    }
    Some(m)
}

/// The triangles an object puts into the front end before culling and clipping, without
/// building them: [`tessellate`]'s count for the canonical objects, 1 for a raw triangle, 2
/// for a quad and 1 for a line or a light point (one primitive each).
pub fn primitive_count(object: &Object) -> u64 {
    let cap = |capped: bool, discs: u64, n: u32| if capped { discs * u64::from(n) } else { 0 };
    match *object {
        Object::Sphere { tessellation, .. } => {
            let n = u64::from(tessellation);
            2 * n * (u64::from((tessellation / 2).max(2)) - 1)
        }
        Object::Torus { tessellation, .. } => {
            2 * u64::from(tessellation) * u64::from((tessellation / 2).max(3))
        }
        Object::Cone {
            tessellation,
            capped,
            ..
        } => u64::from(tessellation) + cap(capped, 1, tessellation),
        Object::Cylinder {
            tessellation,
            capped,
            ..
        } => 2 * u64::from(tessellation) + cap(capped, 2, tessellation),
        Object::Quad { .. } => 2,
        Object::Triangle { .. } | Object::Line { .. } | Object::LightPoint { .. } => 1,
    }
}

/// A flat disc (cap) of `n` triangles around `centre` facing `normal`.
fn disc(m: &mut Mesh, centre: V3, normal: V3, radius: f64, n: u32, radial: &dyn Fn(f64) -> V3) {
    let c = m.vertex(centre, normal);
    let ring = m.positions.len() as u32;
    for j in 0..n {
        let ang = TAU * f64::from(j) / f64::from(n);
        m.vertex(add(centre, scale(radial(ang), radius)), normal);
    }
    for j in 0..n {
        m.tri(c, ring + j, ring + (j + 1) % n);
    }
}
