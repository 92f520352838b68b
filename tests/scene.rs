//! Scene file and host front end.

use igemu::error::FileError;
use igemu::files::TomlFile;
use igemu::scene::*;

// ---------------------------------------------------------------- helpers

/// A minimal valid scene; `{objects}` is replaced by the test's objects.
const BASE: &str = r#"name = "t"
[image]
width = 64
height = 48
background = 0.0

[camera]
position = [0.0, 0.0, 0.0]
look_at = [0.0, 0.0, -1.0]
fov_y_deg = 60.0
near = 1.0
far = 100.0

{objects}"#;

fn scene_text(objects: &str) -> String {
    BASE.replace("{objects}", objects)
}

fn scene(objects: &str) -> Scene {
    let f = TomlFile::from_text("t.toml", &scene_text(objects));
    Scene::from_toml(&f).unwrap_or_else(|e| panic!("{e}"))
}

fn parse_err(text: &str) -> FileError {
    let f = TomlFile::from_text("t.toml", text);
    match Scene::from_toml(&f) {
        Ok(_) => panic!("accepted:\n{text}"),
        Err(e) => e,
    }
}

/// 1-based line of the first line containing `needle`.
fn line_of(text: &str, needle: &str) -> usize {
    text.lines()
        .position(|l| l.contains(needle))
        .expect("needle in text")
        + 1
}

fn triangles(h: &HostScene) -> Vec<[ScreenVertex; 3]> {
    h.prims
        .iter()
        .filter_map(|p| match p {
            Primitive::Triangle(t) => Some(*t),
            _ => None,
        })
        .collect()
}

fn area2(t: &[ScreenVertex; 3]) -> f64 {
    (t[1].x - t[0].x) * (t[2].y - t[0].y) - (t[2].x - t[0].x) * (t[1].y - t[0].y)
}

/// Area of a polygon (x, y) inside the rectangle [0, w] x [0, h] (Sutherland–Hodgman + shoelace).
fn area_in_rect(poly: &[(f64, f64)], w: f64, h: f64) -> f64 {
    let mut p = poly.to_vec();
    let edges: [(usize, f64, bool); 4] =
        [(0, 0.0, true), (0, w, false), (1, 0.0, true), (1, h, false)];
    for (axis, bound, greater) in edges {
        let c = |v: &(f64, f64)| if axis == 0 { v.0 } else { v.1 };
        let d = |v: &(f64, f64)| if greater { c(v) - bound } else { bound - c(v) };
        let mut out = Vec::new();
        for k in 0..p.len() {
            let (a, b) = (p[k], p[(k + 1) % p.len()]);
            if d(&a) >= 0.0 {
                out.push(a);
            }
            if (d(&a) >= 0.0) != (d(&b) >= 0.0) {
                let t = d(&a) / (d(&a) - d(&b));
                out.push((a.0 + t * (b.0 - a.0), a.1 + t * (b.1 - a.1)));
            }
        }
        p = out;
        if p.is_empty() {
            return 0.0;
        }
    }
    let mut s = 0.0;
    for k in 0..p.len() {
        let (a, b) = (p[k], p[(k + 1) % p.len()]);
        s += a.0 * b.1 - b.0 * a.1;
    }
    s.abs() * 0.5
}

fn guard() -> GuardBand {
    GuardBand::around(64, 48, 16.0)
}

// ---------------------------------------------------------------- default scene

#[test]
fn default_scene_loads_and_its_front_end_is_sane() {
    let s = Scene::default_scene();
    assert_eq!(s.name, "default");
    assert_eq!((s.image.width, s.image.height), (640, 480));
    assert_eq!(Scene::embedded("default").as_ref(), Some(&s));
    assert!(Scene::embedded("no such scene").is_none());
    assert!(EMBEDDED.iter().any(|(n, _)| *n == "default"));
    let Lens::ThinLens { focus_distance, .. } = s.camera.lens else {
        panic!("thin lens expected")
    };
    assert_eq!(focus_distance, 10.0);
    assert_eq!(s.display.b_min(), 1.0);
    // cone, sphere, torus from near to far
    assert!(matches!(s.objects[0], Object::Cone { .. }));
    assert!(matches!(s.objects[1], Object::Sphere { .. }));
    assert!(matches!(s.objects[2], Object::Torus { .. }));

    let g = GuardBand::around(640, 480, 64.0);
    let h = front_end(&s, &g);
    assert_eq!((h.width, h.height), (640, 480));
    assert!(h.background[0] > 0.0 && h.background[0] < 0.1);
    let tris = triangles(&h);
    assert!(tris.len() > 1000, "{}", tris.len());
    assert_eq!(h.stats.triangles_out, tris.len());
    assert_eq!(h.stats.vertices, 3 * tris.len());
    assert_eq!(h.stats.objects, 3);
    let mut i_max = 0.0f64;
    let mut i_min = f64::INFINITY;
    for t in &tris {
        for v in t {
            assert!(
                v.x.is_finite()
                    && v.y.is_finite()
                    && v.z.is_finite()
                    && v.i.iter().all(|i| i.is_finite()),
                "{v:?}"
            );
            assert!(g.contains(v.x, v.y), "{v:?}");
            // All three objects are on screen.
            assert!(
                (0.0..=640.0).contains(&v.x) && (0.0..=480.0).contains(&v.y),
                "{v:?}"
            );
            assert!((0.0..=1.0).contains(&v.z), "{v:?}");
            i_max = i_max.max(v.i[0]);
            i_min = i_min.min(v.i[0]);
        }
        assert!(area2(t).abs() > 0.0);
    }
    // A good part of the range: dark gradients up to a highlight near but below 1.
    assert!(i_max > 0.8 && i_max < 1.0, "{i_max}");
    assert!(i_min < 0.1, "{i_min}");
    // Deterministic.
    assert_eq!(front_end(&s, &g), h);
}

#[test]
fn default_scene_file_on_disk_matches_the_embedded_one() {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/src/scene/default.toml");
    assert_eq!(Scene::load(path).unwrap(), Scene::default_scene());
}

#[test]
fn scene_serialises_for_the_report() {
    let s = Scene::default_scene();
    let json = serde_json::to_string(&s).unwrap();
    assert!(json.contains("\"kind\":\"sphere\""), "{json}");
    assert!(json.contains("\"kind\":\"thin_lens\""), "{json}");
}

// ---------------------------------------------------------------- shading

#[test]
fn vertex_shading_matches_a_hand_computed_case() {
    // n = e = +z; light towards (0, 0.6, 0.8) with I = 0.5: n.l = 0.8,
    // h = (0, 0.6, 1.8)/sqrt(3.6): (n.h)^2 = 3.24/3.6 = 0.9.
    // A second light exactly behind (e + l = 0, n.l = -1) adds nothing.
    // i = 0.1 + 0.5 * (0.2 + 0.5 * 0.8) + 0.25 * 0.5 * 0.9 = 0.5125
    let m = Material {
        reflectance: [0.5; 3],
        specular: 0.25,
        shininess: 2.0,
        emissive: [0.1; 3],
    };
    let lights = [
        Light {
            direction: [0.0, 0.6, 0.8],
            intensity: [0.5; 3],
        },
        Light {
            direction: [0.0, 0.0, -1.0],
            intensity: [1.0; 3],
        },
    ];
    let i = shade_vertex(
        [0.0, 0.0, -5.0],
        [0.0, 0.0, 2.0],
        [0.0, 0.0, 0.0],
        &m,
        0.2,
        &lights,
    );
    assert!(i.iter().all(|&i| (i - 0.5125).abs() < 1e-12), "{i:?}");

    // The same through the scene file and the front end: a raw world-space triangle facing
    // the camera with a vertex on the view axis (projected to the screen centre), both windings
    // (raw triangles are two-sided and shaded with the normal facing the eye).
    for verts in [
        "[0.0, 0.0, -5.0], [1.0, 0.0, -5.0], [0.0, 1.0, -5.0]",
        "[0.0, 0.0, -5.0], [0.0, 1.0, -5.0], [1.0, 0.0, -5.0]",
    ] {
        let s = scene(&format!(
            r#"[shading]
ambient = 0.2
[[light]]
direction = [0.0, 3.0, 4.0]
intensity = 0.5
[[light]]
direction = [0.0, 0.0, -1.0]
[[object]]
kind = "triangle"
vertices = [{verts}]
reflectance = 0.5
specular = 0.25
shininess = 2.0
emissive = 0.1
"#
        ));
        let h = front_end(&s, &guard());
        let tris = triangles(&h);
        assert_eq!(tris.len(), 1);
        let v = tris[0][0];
        assert!(
            (v.x - 32.0).abs() < 1e-9 && (v.y - 24.0).abs() < 1e-9,
            "{v:?}"
        );
        assert!((v.i[0] - 0.5125).abs() < 1e-12, "{v:?}");
        assert!((v.z - screen_z(&s.camera, 5.0)).abs() < 1e-12);
    }
}

// ---------------------------------------------------------------- tessellation and culling

#[test]
fn canonical_meshes_are_closed_outward_and_have_the_right_volume() {
    use std::f64::consts::PI;
    let s = scene(
        r#"[[object]]
kind = "sphere"
center = [1.0, 2.0, 3.0]
radius = 2.0
tessellation = 128
[[object]]
kind = "torus"
center = [0.0, 0.0, 0.0]
axis = [1.0, 1.0, 0.0]
major_radius = 3.0
minor_radius = 1.0
tessellation = 128
[[object]]
kind = "cone"
base = [0.0, 1.0, 0.0]
axis = [0.0, 0.0, 3.0]
radius = 1.0
tessellation = 256
[[object]]
kind = "cylinder"
base = [0.0, 1.0, 0.0]
axis = [2.0, 0.0, 0.0]
radius = 0.5
tessellation = 256
"#,
    );
    let exact = [
        4.0 / 3.0 * PI * 8.0,
        2.0 * PI * PI * 3.0,
        PI * 3.0 / 3.0,
        PI * 0.25 * 2.0,
    ];
    for (o, v_exact) in s.objects.iter().zip(exact) {
        let m = tessellate(o).unwrap();
        assert!(m.closed);
        // Signed volume by the divergence theorem: positive iff the winding is outward.
        let mut vol = 0.0;
        for t in &m.triangles {
            let [a, b, c] = t.map(|k| m.positions[k as usize]);
            let cr = [
                b[1] * c[2] - b[2] * c[1],
                b[2] * c[0] - b[0] * c[2],
                b[0] * c[1] - b[1] * c[0],
            ];
            vol += (a[0] * cr[0] + a[1] * cr[1] + a[2] * cr[2]) / 6.0;
        }
        assert!(
            (vol - v_exact).abs() < 0.01 * v_exact,
            "{o:?}: {vol} vs {v_exact}"
        );
        for n in &m.normals {
            assert!(((n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt() - 1.0).abs() < 1e-12);
        }
    }
    assert!(
        tessellate(&Object::LightPoint {
            space: Space::World,
            position: [0.0; 3],
            intensity: [1.0; 3],
            size: 1.0
        })
        .is_none()
    );
}

#[test]
fn sphere_back_faces_are_culled_about_half() {
    // Far away, the visible cap of a sphere is almost a hemisphere.
    let s = scene(
        r#"[[object]]
kind = "sphere"
center = [0.0, 0.0, -90.0]
radius = 0.5
tessellation = 64
"#,
    );
    let h = front_end(&s, &guard());
    let st = &h.stats;
    assert_eq!(st.triangles_in, 2 * 64 * 31);
    let frac = st.culled_backfaces as f64 / st.triangles_in as f64;
    assert!((0.45..=0.55).contains(&frac), "{st:?}");
    assert_eq!(
        st.triangles_out + st.culled_backfaces + st.dropped_degenerate,
        st.triangles_in,
        "{st:?}"
    );
    // Every front face has the same orientation on screen.
    let tris = triangles(&h);
    let first = area2(&tris[0]).signum();
    assert!(tris.iter().all(|t| area2(t).signum() == first));
}

#[test]
fn open_cylinders_are_two_sided() {
    let s = scene(
        r#"[[object]]
kind = "cylinder"
base = [0.0, -1.0, -10.0]
axis = [0.0, 2.0, 0.0]
radius = 1.0
tessellation = 16
capped = false
"#,
    );
    let h = front_end(&s, &guard());
    assert_eq!(h.stats.culled_backfaces, 0);
    assert_eq!(h.stats.triangles_out, 32);
}

// ---------------------------------------------------------------- clipping

#[test]
fn near_plane_clipping_keeps_only_what_is_in_front() {
    // One vertex behind the camera: crosses the near plane (near = 1).
    let s = scene(
        r#"[[object]]
kind = "triangle"
vertices = [[-1.0, -1.0, -5.0], [1.0, -1.0, -5.0], [0.0, 2.0, 5.0]]
intensity = [0.0, 0.5, 1.0]
"#,
    );
    let h = front_end(&s, &GuardBand::around(64, 48, 1e5));
    assert_eq!(h.stats.clipped_near, 1);
    let tris = triangles(&h);
    assert_eq!(tris.len(), 2, "a quadrilateral after the near clip");
    let mut on_near = 0;
    for t in &tris {
        for v in t {
            assert!(v.x.is_finite() && v.y.is_finite() && v.i[0].is_finite());
            assert!((0.0..=1.0).contains(&v.z), "{v:?}");
            assert!(depth_from_screen_z(&s.camera, v.z) >= 1.0 - 1e-12);
            assert!((0.0..=1.0).contains(&v.i[0]));
            if v.z == 0.0 {
                on_near += 1;
            }
        }
    }
    assert!(on_near >= 2);

    // Wholly behind the camera: nothing.
    let s = scene(
        r#"[[object]]
kind = "triangle"
vertices = [[-1.0, -1.0, 5.0], [1.0, -1.0, 5.0], [0.0, 1.0, 5.0]]
intensity = [1.0, 1.0, 1.0]
"#,
    );
    let h = front_end(&s, &guard());
    assert!(h.prims.is_empty());
    assert_eq!(h.stats.dropped_outside, 1);
}

#[test]
fn far_plane_clipping_keeps_z_at_most_one() {
    let s = scene(
        r#"[[object]]
kind = "quad"
vertices = [[-10.0, -3.0, -10.0], [10.0, -3.0, -10.0], [10.0, -3.0, -500.0], [-10.0, -3.0, -500.0]]
"#,
    );
    let h = front_end(&s, &GuardBand::around(64, 48, 1e4));
    assert!(h.stats.clipped_far >= 1, "{:?}", h.stats);
    let tris = triangles(&h);
    assert!(!tris.is_empty());
    assert!(tris.iter().flatten().all(|v| (0.0..=1.0).contains(&v.z)));
    assert!(tris.iter().flatten().any(|v| v.z == 1.0));
}

#[test]
fn guard_band_clipping_preserves_the_on_screen_area_and_the_plane_equations() {
    let (w, hgt) = (64.0, 48.0);
    let orig = [
        ScreenVertex {
            x: -1e6,
            y: -1e6,
            z: 0.1,
            i: [0.0; 3],
        },
        ScreenVertex {
            x: 1e6,
            y: 20.0,
            z: 0.9,
            i: [1.0; 3],
        },
        ScreenVertex {
            x: 30.0,
            y: 1e6,
            z: 0.5,
            i: [2.0; 3],
        },
    ];
    let s = scene(&format!(
        r#"[[object]]
kind = "triangle"
space = "screen"
vertices = [{}]
intensity = [{}]
"#,
        orig.iter()
            .map(|v| format!("[{:?}, {:?}, {:?}]", v.x, v.y, v.z))
            .collect::<Vec<_>>()
            .join(", "),
        orig.iter()
            .map(|v| format!("{:?}", v.i))
            .collect::<Vec<_>>()
            .join(", "),
    ));
    let g = guard();
    let h = front_end(&s, &g);
    assert_eq!(h.stats.clipped_guard, 1);
    let tris = triangles(&h);
    assert!(!tris.is_empty());
    for v in tris.iter().flatten() {
        assert!(g.contains(v.x, v.y), "{v:?}");
    }
    let a_orig = area_in_rect(&orig.map(|v| (v.x, v.y)), w, hgt);
    let a_clip: f64 = tris
        .iter()
        .map(|t| area_in_rect(&t.map(|v| (v.x, v.y)), w, hgt))
        .sum();
    assert!(a_orig > 0.0);
    assert!(
        (a_orig - a_clip).abs() <= 1e-6 * a_orig,
        "{a_orig} vs {a_clip}"
    );
    // z and i of the new vertices lie on the original planes (affine in screen space).
    let plane = |f: fn(&ScreenVertex) -> f64, x: f64, y: f64| {
        let [a, b, c] = &orig;
        let det = (b.x - a.x) * (c.y - a.y) - (c.x - a.x) * (b.y - a.y);
        let l1 = ((x - a.x) * (c.y - a.y) - (c.x - a.x) * (y - a.y)) / det;
        let l2 = ((b.x - a.x) * (y - a.y) - (x - a.x) * (b.y - a.y)) / det;
        f(a) + l1 * (f(b) - f(a)) + l2 * (f(c) - f(a))
    };
    for v in tris.iter().flatten() {
        assert!((v.z - plane(|v| v.z, v.x, v.y)).abs() < 1e-6, "{v:?}");
        assert!((v.i[0] - plane(|v| v.i[0], v.x, v.y)).abs() < 1e-6, "{v:?}");
    }

    // Entirely outside the band: dropped.
    let s = scene(
        r#"[[object]]
kind = "triangle"
space = "screen"
vertices = [[1000.0, 0.0, 0.5], [2000.0, 0.0, 0.5], [1500.0, 40.0, 0.5]]
intensity = [1.0, 1.0, 1.0]
"#,
    );
    let h = front_end(&s, &g);
    assert!(h.prims.is_empty());
    assert_eq!(h.stats.dropped_outside, 1);
}

#[test]
fn lines_and_points_are_clipped() {
    let s = scene(
        r#"[[object]]
kind = "line"
from = [0.0, 0.0, -5.0]
to = [0.0, 0.0, 5.0]
intensity = 0.5
[[object]]
kind = "line"
space = "screen"
from = [-1e6, 10.0, 0.5]
to = [1e6, 10.0, 0.5]
intensity = 0.5
width = 2.0
[[object]]
kind = "light_point"
position = [0.0, 0.0, -200.0]
intensity = 1.0
[[object]]
kind = "light_point"
position = [0.0, 0.0, 5.0]
intensity = 1.0
[[object]]
kind = "light_point"
position = [0.0, 0.0, -50.0]
intensity = 3.0
size = 2.0
"#,
    );
    let g = guard();
    let h = front_end(&s, &g);
    assert_eq!((h.stats.lines, h.stats.points), (2, 1));
    let Primitive::Line { a, b, .. } = h.prims[0] else {
        panic!()
    };
    // From the centre at depth 5 to the near plane, both on the view axis.
    assert!(
        (a.z - screen_z(&s.camera, 5.0)).abs() < 1e-12 && b.z == 0.0,
        "{a:?} {b:?}"
    );
    let Primitive::Line { a, b, width } = h.prims[1] else {
        panic!()
    };
    assert_eq!(width, 2.0);
    assert_eq!((a.x, b.x, a.y, b.y), (g.x_min, g.x_max, 10.0, 10.0));
    let Primitive::Point { v, size } = h.prims[2] else {
        panic!()
    };
    assert_eq!(size, 2.0);
    assert!((v.x - 32.0).abs() < 1e-12 && (v.y - 24.0).abs() < 1e-12 && v.i == [3.0; 3]);
    assert!((v.z - screen_z(&s.camera, 50.0)).abs() < 1e-12);
}

#[test]
fn z_mapping_round_trips() {
    let s = scene("");
    let cam = &s.camera;
    assert_eq!(screen_z(cam, cam.near), 0.0);
    assert_eq!(screen_z(cam, cam.far), 1.0);
    for k in 0..=100 {
        let d = cam.near * (cam.far / cam.near).powf(f64::from(k) / 100.0);
        let z = screen_z(cam, d);
        assert!((0.0..=1.0).contains(&z));
        assert!((depth_from_screen_z(cam, z) - d).abs() <= 1e-12 * d, "{d}");
        let z2 = f64::from(k) / 100.0;
        assert!((screen_z(cam, depth_from_screen_z(cam, z2)) - z2).abs() < 1e-12);
    }
}

#[test]
fn screen_space_primitives_pass_through_unchanged() {
    let s = scene(
        r#"[[object]]
kind = "triangle"
space = "screen"
vertices = [[1.5, 2.25, 0.0], [60.0, 3.0, 0.5], [10.0, 47.0, 1.0]]
intensity = [0.0, 0.5, 1.5]
[[object]]
kind = "quad"
space = "screen"
vertices = [[0.0, 0.0, 0.2], [64.0, 0.0, 0.2], [64.0, 48.0, 0.3], [0.0, 48.0, 0.3]]
intensity = [0.1, 0.2, 0.3, 0.4]
[[object]]
kind = "line"
space = "screen"
from = [0.5, 0.5, 0.25]
to = [63.5, 40.0, 0.75]
intensity = 0.7
[[object]]
kind = "light_point"
space = "screen"
position = [20.5, 30.5, 0.125]
intensity = 4.0
size = 3.0
"#,
    );
    let h = front_end(&s, &guard());
    let v = |x, y, z, i| ScreenVertex { x, y, z, i };
    let expected = vec![
        Primitive::Triangle([
            v(1.5, 2.25, 0.0, [0.0; 3]),
            v(60.0, 3.0, 0.5, [0.5; 3]),
            v(10.0, 47.0, 1.0, [1.5; 3]),
        ]),
        Primitive::Triangle([
            v(0.0, 0.0, 0.2, [0.1; 3]),
            v(64.0, 0.0, 0.2, [0.2; 3]),
            v(64.0, 48.0, 0.3, [0.3; 3]),
        ]),
        Primitive::Triangle([
            v(0.0, 0.0, 0.2, [0.1; 3]),
            v(64.0, 48.0, 0.3, [0.3; 3]),
            v(0.0, 48.0, 0.3, [0.4; 3]),
        ]),
        Primitive::Line {
            a: v(0.5, 0.5, 0.25, [0.7; 3]),
            b: v(63.5, 40.0, 0.75, [0.7; 3]),
            width: 1.0,
        },
        Primitive::Point {
            v: v(20.5, 30.5, 0.125, [4.0; 3]),
            size: 3.0,
        },
    ];
    assert_eq!(h.prims, expected);
    assert_eq!(h.stats.vertices, 3 * 3 + 2 + 1);
    assert_eq!(h.stats.triangles_in, 3);
}

// ---------------------------------------------------------------- validation

fn assert_err(text: &str, field: &str, needle_line: &str, msg_has: &str) {
    let e = parse_err(text);
    assert_eq!(e.field, field, "{e}");
    assert_eq!(e.line, Some(line_of(text, needle_line)), "{e}");
    assert!(e.msg.contains(msg_has), "{e}");
    assert_eq!(e.file, "t.toml");
}

#[test]
fn malformed_toml_has_a_line() {
    let text = scene_text("[[object]\nkind = \"sphere\"\n");
    let e = parse_err(&text);
    assert_eq!(e.line, Some(line_of(&text, "[[object]")), "{e}");
}

#[test]
fn unknown_fields_and_kinds_are_rejected() {
    let text =
        scene_text("[[object]]\nkind = \"sphere\"\ncenter = [0, 0, -5]\nradius = 1\nradiuss = 2\n");
    let e = parse_err(&text);
    assert_eq!(e.line, Some(line_of(&text, "radiuss")), "{e}");
    assert_eq!(e.field, "object[0].radiuss", "{e}");
    // The fields of the object's own kind, not of every kind.
    assert!(
        e.msg.contains("unknown field `radiuss` for an object of kind \"sphere\"; allowed: `kind`, `center`, `radius`, `tessellation`,"),
        "{e}"
    );
    assert!(!e.msg.contains("major_radius"), "{e}");
    // An unknown kind as well: serde's list of every field stays.
    let text = scene_text("[[object]]\nkind = \"pyramid\"\nradiuss = 2\n");
    let e = parse_err(&text);
    assert!(
        e.msg.contains("unknown field `radiuss`; allowed: `kind`,"),
        "{e}"
    );

    let text = scene_text("[[object]]\nkind = \"pyramid\"\n");
    assert_err(
        &text,
        "object[0].kind",
        "pyramid",
        "unknown object kind \"pyramid\"",
    );
    let e = parse_err(&text);
    assert!(e.msg.contains("light_point"), "{e}");

    // A field of another kind.
    let text = scene_text(
        "[[object]]\nkind = \"torus\"\ncenter = [0, 0, -5]\naxis = [0, 1, 0]\nmajor_radius = 2\nminor_radius = 1\nradius = 3\n",
    );
    assert_err(
        &text,
        "object[0].radius",
        "radius = 3",
        "does not apply to kind = \"torus\"",
    );

    // Unknown top-level table.
    let text = scene_text("[lighting]\nambient = 0.1\n");
    let e = parse_err(&text);
    assert_eq!(e.line, Some(line_of(&text, "[lighting]")), "{e}");
}

#[test]
fn nan_inf_and_ranges_are_rejected_with_the_field_and_line() {
    let sphere = |r: &str| {
        scene_text(&format!(
            "[[object]]\nkind = \"sphere\"\ncenter = [0, 0, -5]\nradius = {r}\n"
        ))
    };
    assert_err(
        &sphere("nan"),
        "object[0].radius",
        "radius",
        "must be a finite number in [1e-9, 1e9], got NaN",
    );
    assert_err(
        &sphere("-1"),
        "object[0].radius",
        "radius",
        "must be a finite number in [1e-9, 1e9], got -1",
    );
    assert_err(&sphere("inf"), "object[0].radius", "radius", "got inf");
    let text = scene_text("[[object]]\nkind = \"sphere\"\ncenter = [0, -inf, -5]\nradius = 1\n");
    assert_err(&text, "object[0].center[1]", "center", "finite");

    let text = BASE
        .replace("width = 64", "width = 0")
        .replace("{objects}", "");
    assert_err(&text, "image.width", "width = 0", "1..=8192, got 0");
    let text = BASE
        .replace("width = 64", "width = 8193")
        .replace("{objects}", "");
    assert_err(&text, "image.width", "width = 8193", "1..=8192");
    assert_eq!(MAX_RESOLUTION, 8192);
    let text = BASE
        .replace("far = 100.0", "far = 1.0")
        .replace("{objects}", "");
    assert_err(&text, "camera.far", "far = 1.0", "> camera.near");
    let text = BASE
        .replace("near = 1.0", "near = 0.0")
        .replace("{objects}", "");
    assert_err(&text, "camera.near", "near = 0.0", "in [1e-9, 1e9], got 0");
    let text = BASE
        .replace("fov_y_deg = 60.0", "fov_y_deg = 180.0")
        .replace("{objects}", "");
    assert_err(&text, "camera.fov_y_deg", "fov_y_deg", "in [0.001, 180)");
    let text = BASE
        .replace("background = 0.0", "background = 1.5")
        .replace("{objects}", "");
    assert_err(&text, "image.background", "background", "in [0, 1]");
    let text = BASE
        .replace("fov_y_deg = 60.0", "up = [0.0, 0.0, 2.0]")
        .replace("{objects}", "");
    assert_err(&text, "camera.up", "up =", "parallel");

    let display = |f: &str| scene_text(&format!("[display]\n{f}\n"));
    assert_err(
        &display("contrast = 1.0"),
        "display.contrast",
        "contrast",
        "in [2, 1e9]",
    );
    assert_err(&display("gamma = 5.5"), "display.gamma", "gamma", "(1, 5]");
    assert_err(
        &display("weber = 1.0"),
        "display.weber",
        "weber",
        "[0.001, 0.5]",
    );
    assert_err(
        &display("b_max = -3"),
        "display.b_max",
        "b_max",
        "[0.01, 1e6]",
    );

    let light = scene_text("[[light]]\ndirection = [0, 1, 0]\nintensity = -0.5\n");
    assert_err(&light, "light[0].intensity", "intensity", "in [0, 1e6]");
    let light = scene_text("[[light]]\ndirection = [0, 0, 0]\n");
    assert_err(&light, "light[0].direction", "direction", "non-zero");

    let cone = |f: &str| {
        scene_text(&format!(
            "[[object]]\nkind = \"cone\"\nbase = [0, 0, -5]\nradius = 1\n{f}\n"
        ))
    };
    assert_err(
        &cone("axis = [0, 0, 0]"),
        "object[0].axis",
        "axis",
        "non-zero",
    );
    assert_err(
        &cone("axis = [0, 1, 0]\ntessellation = 2"),
        "object[0].tessellation",
        "tessellation",
        "3..=1024",
    );
    let e = parse_err(&cone(""));
    assert_eq!(e.field, "object[0].axis", "{e}");
    assert!(e.msg.contains("missing field `axis`"), "{e}");

    let torus = scene_text(
        "[[object]]\nkind = \"torus\"\ncenter = [0, 0, -5]\naxis = [0, 1, 0]\nmajor_radius = 1\nminor_radius = 1\n",
    );
    assert_err(
        &torus,
        "object[0].minor_radius",
        "minor_radius",
        "< major_radius",
    );
}

#[test]
fn screen_space_and_lens_rules() {
    let tri = |extra: &str| {
        scene_text(&format!(
            "[[object]]\nkind = \"triangle\"\nspace = \"screen\"\nvertices = [[0, 0, 0.5], [10, 0, 0.5], [0, 10, 1.5]]\n{extra}\n"
        ))
    };
    assert_err(
        &tri("intensity = [1, 1, 1]"),
        "object[0].vertices[2][2]",
        "vertices",
        "[0, 1]",
    );
    let ok = "vertices = [[0, 0, 0.5], [10, 0, 0.5], [0, 10, 0.5]]";
    let t = tri("").replace("vertices = [[0, 0, 0.5], [10, 0, 0.5], [0, 10, 1.5]]", ok);
    let e = parse_err(&t);
    assert!(e.msg.contains("missing field `intensity`"), "{e}");
    let t = tri("intensity = [1, -1, 1]")
        .replace("vertices = [[0, 0, 0.5], [10, 0, 0.5], [0, 10, 1.5]]", ok);
    assert_err(&t, "object[0].intensity[1]", "intensity", "in [0, 1e6]");
    let t = tri("intensity = [1, 1]")
        .replace("vertices = [[0, 0, 0.5], [10, 0, 0.5], [0, 10, 1.5]]", ok);
    assert_err(
        &t,
        "object[0].intensity",
        "intensity",
        "an array of 3 intensities",
    );
    let t = tri("intensity = [1, 1, 1]\nreflectance = 0.5")
        .replace("vertices = [[0, 0, 0.5], [10, 0, 0.5], [0, 10, 1.5]]", ok);
    assert_err(&t, "object[0].reflectance", "reflectance", "no effect");
    let t = tri("intensity = [1, 1, 1]").replace("space = \"screen\"", "space = \"clip\"");
    assert_err(&t, "object[0].space", "space", "\"world\", \"screen\"");

    let lens = |body: &str| BASE.replace("{objects}", &format!("[camera.lens]\n{body}\n"));
    let both = lens(
        "kind = \"thin_lens\"\nfocal_length = 0.05\nf_number = 2\nlens_radius = 0.01\nfocus_distance = 10",
    );
    assert_err(&both, "camera.lens.lens_radius", "lens_radius", "not both");
    let f = Scene::from_toml(&TomlFile::from_text(
        "t.toml",
        &lens("kind = \"thin_lens\"\nfocal_length = 0.05\nf_number = 2\nfocus_distance = 10"),
    ))
    .unwrap();
    let Lens::ThinLens {
        lens_radius,
        coc,
        deep,
        ..
    } = f.camera.lens
    else {
        panic!()
    };
    assert!((lens_radius - 0.0125).abs() < 1e-15);
    assert!((coc - 0.035 * 0.05 / 50.0).abs() < 1e-18);
    assert_eq!(deep, 0.0);
    let near_focus =
        lens("kind = \"thin_lens\"\nfocal_length = 0.05\nf_number = 2\nfocus_distance = 0.05");
    assert_err(
        &near_focus,
        "camera.lens.focus_distance",
        "focus_distance",
        "> focal_length",
    );
    let pin = lens("kind = \"pinhole\"\nfocal_length = 0.05");
    assert_err(&pin, "camera.lens.focal_length", "focal_length", "pinhole");
    let bad = lens("kind = \"fisheye\"");
    assert_err(&bad, "camera.lens.kind", "fisheye", "thin_lens");
}

#[test]
fn errors_from_files_on_disk_name_the_file() {
    let dir = std::env::temp_dir().join(format!("igemu-scene-test-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("bad.toml");
    let text = scene_text("[[object]]\nkind = \"sphere\"\ncenter = [0, 0, -5]\nradius = -2\n");
    std::fs::write(&path, &text).unwrap();
    let p = path.to_str().unwrap();
    let e = Scene::load(p).unwrap_err();
    assert_eq!(e.file, p);
    assert_eq!(e.field, "object[0].radius");
    assert_eq!(e.line, Some(line_of(&text, "radius = -2")));
    assert!(
        e.to_string()
            .contains(&format!("{p}:{}", line_of(&text, "radius = -2"))),
        "{e}"
    );

    let good = dir.join("good.toml");
    std::fs::write(
        &good,
        BASE.replace("name = \"t\"\n", "").replace("{objects}", ""),
    )
    .unwrap();
    assert_eq!(Scene::load(good.to_str().unwrap()).unwrap().name, "good");

    let missing = Scene::load(dir.join("missing.toml").to_str().unwrap()).unwrap_err();
    assert!(missing.msg.contains("cannot read"), "{missing}");
    std::fs::remove_dir_all(&dir).unwrap();
}

// ---------------------------------------------------------------- bounds (issue 13)

/// The bounds that keep every loop finite accept their edges, refuse beyond them, and the
/// widest accepted line and light point render at once (a line of width 1e308 hung).
#[test]
fn line_widths_point_sizes_and_the_lens_are_bounded() {
    // 64 x 48: diagonal 80, bound 2 (80 + 2 * 4096) = 16544 pixels.
    let widest = "[[object]]\nkind = \"line\"\nspace = \"screen\"\nfrom = [-10, 5, 0.5]\nto = [70, 40, 0.5]\nintensity = 1\nwidth = 16544\n\n[[object]]\nkind = \"light_point\"\nspace = \"screen\"\nposition = [20, 20, 0.4]\nintensity = 1\nsize = 16544\n";
    let s = scene(widest);
    let t = std::time::Instant::now();
    let hw = igemu::config::HwConfig::default_config();
    let r = igemu::pipeline::render(&s, &hw, igemu::stage::RunOptions::FAST).unwrap();
    assert!(r.dac.iter().all(|&c| c > 0), "the line covers the screen");
    assert!(t.elapsed().as_secs() < 30, "{:?}", t.elapsed());
    let wider = scene_text(&widest.replacen("width = 16544", "width = 16544.5", 1));
    assert_err(
        &wider,
        "object[0].width",
        "width = 16544.5",
        "(0, 16544] pixels",
    );
    let huge = scene_text(&widest.replacen("size = 16544", "size = 1e308", 1));
    assert_err(&huge, "object[1].size", "size = 1e308", "got 1e308");

    // A view volume at least 0.1 % deep (the background's screen depth stays <= 1001).
    let thin = BASE
        .replace("far = 100.0", "far = 1.0005")
        .replace("{objects}", "");
    assert_err(
        &thin,
        "camera.far",
        "far = 1.0005",
        "at least 1.001 camera.near",
    );

    // The lens: lens_radius up to camera.near (1 in BASE), f_number down to F / (2 near).
    let lens = |body: &str| {
        BASE.replace("{objects}", &format!("[camera.lens]\nkind = \"thin_lens\"\nfocal_length = 0.05\nfocus_distance = 10\n{body}\n"))
    };
    let ok = |body: &str| Scene::from_toml(&TomlFile::from_text("t.toml", &lens(body))).unwrap();
    ok("lens_radius = 1.0");
    ok("f_number = 0.025");
    for (body, field, has) in [
        (
            "lens_radius = 1.0001",
            "camera.lens.lens_radius",
            "camera.near = 1",
        ),
        (
            "lens_radius = 1e308",
            "camera.lens.lens_radius",
            "[1e-9, 1e9], got 1e308",
        ),
        (
            "lens_radius = 1e50",
            "camera.lens.lens_radius",
            "[1e-9, 1e9], got 1e50",
        ),
        (
            "f_number = 0.024",
            "camera.lens.f_number",
            "f_number must be >= focal_length / (2 camera.near) = 0.025",
        ),
        (
            "f_number = 1e-308",
            "camera.lens.f_number",
            "[0.001, 1e6], got 1e-308",
        ),
        ("f_number = 1e308", "camera.lens.f_number", "[0.001, 1e6]"),
        (
            "lens_radius = 0.01\ncoc = 1e300",
            "camera.lens.coc",
            "[1e-9, 1e9]",
        ),
        (
            "lens_radius = 0.01\ndeep = inf",
            "camera.lens.deep",
            "[0, 1e9]",
        ),
    ] {
        let needle = body.lines().last().unwrap();
        assert_err(&lens(body), field, needle, has);
    }
}

/// Vectors are exactly 3 finite numbers: a 4th element (even a string) is refused, not
/// ignored.
#[test]
fn vectors_have_exactly_three_numbers() {
    for (from, to, field) in [
        (
            "position = [0.0, 0.0, 0.0]",
            "position = [0.0, 0.0, 0.0, 5.0]",
            "camera.position",
        ),
        (
            "look_at = [0.0, 0.0, -1.0]",
            "look_at = [0, 0, -1, \"junk\"]",
            "camera.look_at",
        ),
        (
            "look_at = [0.0, 0.0, -1.0]",
            "look_at = [0, 0]",
            "camera.look_at",
        ),
    ] {
        let text = BASE.replace(from, to).replace("{objects}", "");
        assert_err(&text, field, to, "exactly 3 finite numbers");
    }
    let text = scene_text(
        "[[object]]\nkind = \"quad\"\nvertices = [[0, 0, -5], [1, 0, -5], [1, 1, -5], [0, 1, -5, 9]]\n",
    );
    assert_err(
        &text,
        "object[0].vertices[3]",
        "vertices",
        "got an array of 4 values",
    );
}

/// `primitive_count` is what the front end gets, and a scene is limited to `MAX_PRIMITIVES`
/// (memory grows with the primitives: five spheres at the largest tessellation are refused,
/// naming the fifth's tessellation).
#[test]
fn primitives_are_counted_and_bounded() {
    for t in [3, 4, 5, 16, 33] {
        for capped in [true, false] {
            let objects = format!(
                "[[object]]\nkind = \"sphere\"\ncenter = [0, 0, -5]\nradius = 1\ntessellation = {t}\n\n\
                 [[object]]\nkind = \"torus\"\ncenter = [0, 0, -5]\naxis = [0, 1, 0]\nmajor_radius = 2\nminor_radius = 1\ntessellation = {t}\n\n\
                 [[object]]\nkind = \"cone\"\nbase = [0, 0, -5]\naxis = [0, 1, 0]\nradius = 1\ntessellation = {t}\ncapped = {capped}\n\n\
                 [[object]]\nkind = \"cylinder\"\nbase = [0, 0, -5]\naxis = [0, 1, 0]\nradius = 1\ntessellation = {t}\ncapped = {capped}\n"
            );
            for o in &scene(&objects).objects {
                let m = tessellate(o).unwrap();
                assert_eq!(primitive_count(o), m.triangles.len() as u64, "{o:?}");
            }
        }
    }
    let s = scene(&format!(
        "{}{}",
        tri_block(),
        "[[object]]\nkind = \"quad\"\nvertices = [[0, 0, -5], [1, 0, -5], [1, 1, -5], [0, 1, -5]]\n"
    ));
    let h = front_end(&s, &GuardBand::around(64, 48, 16.0));
    let counted: u64 = s.objects.iter().map(primitive_count).sum();
    assert_eq!(counted, h.stats.triangles_in as u64);

    let sphere =
        "[[object]]\nkind = \"sphere\"\ncenter = [0, 0, -5]\nradius = 1\ntessellation = 1024\n\n";
    scene(&sphere.repeat(4));
    let text = scene_text(&sphere.repeat(5));
    let e = parse_err(&text);
    assert_eq!(e.field, "object[4].tessellation", "{e}");
    assert!(e.msg.contains("more than the 4194304"), "{e}");
}

fn tri_block() -> &'static str {
    "[[object]]\nkind = \"triangle\"\nvertices = [[0, 0, -5], [1, 0, -5], [0, 1, -5]]\n\n"
}
