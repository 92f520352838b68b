//! Accumulate: equal energy of box and tent (and the Gaussian's ripple), exact kernel
//! sums, and frame-memory overflow handling.

mod common;

use common::{hw, point, scene, tri};
use igemu::config::FilterKind;
use igemu::fixed::{Overflow, QFormat};
use igemu::pipeline::render;
use igemu::stage::RunOptions;
use proptest::prelude::*;

/// Total of the frame memory over the image, in frame LSBs.
fn total(objects: &str, filter: FilterKind, frame_frac: u32, n: u32) -> u64 {
    let s = scene(16, 16, 0.0, objects);
    let h = hw("linear12", |h| {
        h.accumulate.filter = filter;
        h.raster.samples = n;
        h.accumulate.frame.format = QFormat::new(false, 12, frame_frac);
    });
    let r = render(&s, &h, RunOptions::FAST).expect("render");
    r.frame().acc.iter().map(|&a| a as u64).sum()
}

fn quad(x: f64, y: f64, side: f64, i: f64) -> String {
    let (a, b, c, d) = (
        [x, y, 0.5],
        [x + side, y, 0.5],
        [x + side, y + side, 0.5],
        [x, y + side, 0.5],
    );
    tri([a, b, c], [i; 3]) + &tri([a, c, d], [i; 3])
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(40))]

    /// (b) Equal energy: with a frame format wide enough to hold every product exactly
    /// (14 fraction bits = 10 weight + 4 intensity), a light point or a quad of one
    /// sample or of one pixel accumulates exactly the same total at every sub-pixel
    /// position with box and tent.
    #[test]
    fn equal_energy_box_and_tent(x in 4.0f64..11.0, y in 4.0f64..11.0, i in 0.05f64..0.9, n_log in 1u32..4) {
        let n = 1 << n_log;
        for filter in [FilterKind::Box, FilterKind::Tent] {
            for side in [1.0 / n as f64, 1.0] {
                let reference = total(&point(8.0, 8.0, 0.5, i, side), filter, 14, n);
                prop_assert!(reference > 0);
                prop_assert_eq!(total(&point(x, y, 0.5, i, side), filter, 14, n), reference);
                prop_assert_eq!(total(&quad(x, y, side, i), filter, 14, n), reference);
            }
        }
    }
}

#[test]
fn gaussian_total_varies_with_position() {
    let mut totals = std::collections::BTreeSet::new();
    // A one-sample light point: each sample phase of the Gaussian gives a different total.
    // (A one-pixel point covers every phase once and so conserves even the Gaussian's total.)
    for k in 0..16 {
        let x = 8.0 + k as f64 / 16.0;
        totals.insert(total(
            &point(x, 8.0 + k as f64 / 32.0, 0.5, 0.5, 0.25),
            FilterKind::Gaussian,
            14,
            4,
        ));
    }
    assert!(totals.len() >= 3, "the Gaussian should ripple: {totals:?}");
    let (lo, hi) = (
        *totals.first().unwrap() as f64,
        *totals.last().unwrap() as f64,
    );
    eprintln!(
        "Gaussian sigma 0.5 ripple in total energy: {:.2} %",
        100.0 * (hi - lo) / hi
    );
    assert!((hi - lo) / hi > 0.005);
}

#[test]
fn rounded_frame_memory_varies_by_at_most_half_an_lsb_per_touched_pixel() {
    // With the preset UQ12.0 frame each pixel's product is rounded once: the total may
    // differ from the exact one by at most 1/2 LSB per pixel the point touches (9 with tent).
    let exact = total(&point(8.0, 8.0, 0.5, 0.37, 1.0), FilterKind::Tent, 14, 4) as f64 / 16384.0;
    for k in 0..32 {
        let x = 8.0 + k as f64 / 32.0;
        let t = total(&point(x, 7.3, 0.5, 0.37, 1.0), FilterKind::Tent, 0, 4) as f64;
        assert!((t - exact).abs() <= 4.5, "{t} vs {exact}");
    }
}

fn many_lights(overflow: Overflow) -> igemu::error::Result<igemu::pipeline::Render> {
    let objects: String = (0..12).map(|_| point(8.0, 8.0, 0.3, 0.5, 2.0)).collect();
    let s = scene(16, 16, 0.0, &objects);
    let h = hw("linear12", |h| h.accumulate.frame.overflow = overflow);
    render(&s, &h, RunOptions::default())
}

#[test]
fn saturation_at_full_white_under_many_overlapping_lights() {
    let r = many_lights(Overflow::Sat).expect("render");
    assert_eq!(*r.frame().acc.iter().max().unwrap(), 4095);
    assert!(r.report.overflows > 0, "saturation must be counted");
    assert_eq!(*r.dac.iter().max().unwrap(), 255);
    // The float reference clips at white too: the saturated centre matches.
    let centre = 8 * 16 + 8;
    assert_eq!(r.dac[centre], r.dac_ref[centre]);

    let wrapped = many_lights(Overflow::Wrap).expect("render");
    assert!(wrapped.report.overflows > 0);
    assert!(wrapped.frame().acc[centre] < 4095, "WRAP wraps");

    match many_lights(Overflow::Error) {
        Err(igemu::error::Error::Overflow { signal, .. }) => assert_eq!(signal, "accumulate.frame"),
        Err(e) => panic!("unexpected error {e}"),
        Ok(_) => panic!("ERROR mode must stop"),
    }
}

// ---------------------------------------------------------------------------------------
// The fast fixed kernel against the straightforward one.

use igemu::fixed::{SignalStats, round_shift_i64};
use igemu::stage::accumulate::{self as acc, AccParams, AccWork, Frame, PointFrags};
use igemu::stage::visibility::{BACKGROUND, Samples};
use igemu::stage::{Region, StageId, Tiles};
use std::collections::BTreeMap;

type Out = (Frame, AccWork, Vec<SignalStats>, Vec<u64>);

/// The straightforward fixed model (the implementation before the window kernel): every
/// pixel's window grouped by primitive in a map (samples of zero weight skipped), each sum
/// rounded once and added in id order, the statistics recorded per row and merged in row
/// order; then the light points.
fn reference(
    s: &Samples,
    region: &Region,
    tiles: Option<&Tiles>,
    points: &[PointFrags<u32>],
    p: &AccParams,
    bg_i: u32,
    size: (u32, u32),
) -> igemu::error::Result<Out> {
    let k = &p.kernel;
    let sh = p.product_shift();
    let product = |sum: i64, st: &mut SignalStats| -> i64 {
        if sh <= 0 {
            let v = (sum as i128) << (-sh);
            st.record(v as f64, v, false);
            v as i64
        } else {
            let r = round_shift_i64(sum, sh as u32, p.frame.quant) as i128;
            st.record(sum as f64 / (1u64 << sh) as f64, r, false);
            r as i64
        }
    };
    let add = |a: i64, part: i64, ov: &mut u64| -> igemu::error::Result<i64> {
        let q = p.frame.handle_overflow(a as i128 + part as i128);
        if q.overflow {
            *ov += 1;
            if p.frame.overflow == Overflow::Error {
                return Err(igemu::error::Error::Overflow {
                    signal: "accumulate.frame".into(),
                    format: p.frame.format.to_string(),
                    value: a as i128 + part as i128,
                    min: p.frame.format.min_code(),
                    max: p.frame.format.max_code(),
                });
            }
        }
        Ok(q.code)
    };
    let (width, height) = size;
    let npix = width as usize * height as usize;
    let bg = p.background_code(bg_i)?;
    let mut f = Frame {
        width,
        height,
        acc: vec![bg; npix],
        depth: vec![u32::MAX; npix],
        coverage: vec![0; npix],
    };
    let mut work = AccWork::default();
    let mut stats = SignalStats::new("accumulate.product", p.frame.format);
    let mut frame_stats = SignalStats::new("accumulate.frame", p.frame.format);
    let mut rmw = vec![0u64; tiles.map_or(0, |t| t.touched.len())];
    let sw = s.reg.width();
    let n = k.n as usize;
    for py in region.y0..region.y1 {
        let mut row_stats = SignalStats::new("accumulate.product", p.frame.format);
        for px in region.x0..region.x1 {
            if tiles.is_some_and(|t| !t.is_touched(px, py)) {
                continue;
            }
            work.pixels += 1;
            let c0 = (px as i64 * k.n as i64 - k.off - s.reg.c0) as usize;
            let r0 = (py as i64 * k.n as i64 - k.off - s.reg.k0) as usize;
            let mut groups: BTreeMap<u32, i64> = BTreeMap::new();
            for j in 0..k.size {
                for i in 0..k.size {
                    let w = k.w[j * k.size + i];
                    if w != 0 {
                        let at = (r0 + j) * sw + c0 + i;
                        *groups.entry(s.prim[at]).or_default() += w as i64 * s.i[at] as i64;
                    }
                }
            }
            work.macs += (k.size * k.size) as u64;
            let mut a = 0i64;
            for &sum in groups.values() {
                let part = product(sum, &mut row_stats);
                a = add(a, part, &mut work.overflows)?;
            }
            work.fragments += groups.len() as u64;
            if let Some(t) = tiles {
                rmw[t.index(px, py)] += groups.len() as u64;
            }
            let (mut zmin, mut cov) = (u32::MAX, 0u16);
            for j in 0..n {
                for i in 0..n {
                    let at = (r0 + k.off as usize + j) * sw + c0 + k.off as usize + i;
                    if s.prim[at] != BACKGROUND {
                        cov += 1;
                        zmin = zmin.min(s.z[at]);
                    }
                }
            }
            let at = py as usize * width as usize + px as usize;
            f.acc[at] = a as u32;
            f.depth[at] = zmin;
            f.coverage[at] = cov;
        }
        stats.merge(&row_stats);
    }
    for pt in points {
        for (px, py, sw_sum) in acc::point_weights(pt, &s.reg, region, k, |e| k.w[e] as f64) {
            let part = product(pt.i as i64 * sw_sum as i64, &mut stats);
            let at = py as usize * width as usize + px as usize;
            f.acc[at] = add(f.acc[at] as i64, part, &mut work.overflows)? as u32;
            work.point_updates += 1;
            if let Some(t) = tiles {
                rmw[t.index(px, py)] += 1;
            }
        }
    }
    for &a in &f.acc {
        frame_stats.record_code(a as i128);
    }
    frame_stats.add_overflows(work.overflows);
    Ok((f, work, vec![stats, frame_stats], rmw))
}

/// Runs the fast and the straightforward fixed models on a scene's fixed samples (binned
/// tiles and the whole region) and asserts every output, count and statistic is identical.
fn assert_same_as_reference(s: &igemu::scene::Scene, h: &igemu::config::HwConfig, what: &str) {
    let (plan, taps) =
        igemu::pipeline::run_through(s, h, RunOptions::FAST, StageId::Visibility).expect(what);
    let tap = taps.fixed.samples();
    let p = AccParams {
        kernel: acc::kernel(h),
        i_frac: h.input.intensity.format.frac_bits,
        i_max: u32::MAX,
        frame: h.accumulate.frame,
    };
    let size = (plan.layout.grid.width, plan.layout.grid.height);
    let l = &plan.layout;
    for tiles in [Some(&l.tiles), None] {
        let fast = acc::accumulate_tiles(
            &tap.samples,
            &l.region,
            tiles,
            &tap.points,
            &p,
            tap.bg,
            size,
            &igemu::stage::Pool::new(),
        );
        let slow = reference(
            &tap.samples,
            &l.region,
            tiles,
            &tap.points,
            &p,
            tap.bg,
            size,
        );
        match (fast, slow) {
            (Ok(a), Ok(b)) => {
                assert!(
                    a.0 == b.0,
                    "{what}: frame differs (tiles {})",
                    tiles.is_some()
                );
                assert_eq!(a.1, b.1, "{what}: work");
                assert_eq!(
                    format!("{:?}", a.2),
                    format!("{:?}", b.2),
                    "{what}: signals"
                );
                assert_eq!(a.3, b.3, "{what}: frame writes per tile");
            }
            (Err(a), Err(b)) => assert_eq!(a.to_string(), b.to_string(), "{what}"),
            (a, b) => panic!(
                "{what}: fast ok {} vs reference ok {}",
                a.is_ok(),
                b.is_ok()
            ),
        }
    }
}

fn embedded(name: &str, size: Option<(u32, u32)>) -> igemu::scene::Scene {
    let mut s = igemu::scene::Scene::embedded(name).expect("embedded scene");
    if let Some((w, h)) = size {
        s.image.width = w;
        s.image.height = h;
    }
    s
}

#[test]
fn fast_kernel_matches_the_reference_on_the_embedded_scenes() {
    for name in ["default", "default-pinhole", "cone-focus"] {
        for preset in ["linear12", "log8-potentiate", "log8-logadd"] {
            let s = embedded(name, None);
            let h = hw(preset, |_| {});
            assert_same_as_reference(&s, &h, &format!("{name} {preset}"));
        }
    }
}

#[test]
fn fast_kernel_matches_the_reference_for_every_filter_and_sample_count() {
    for name in ["default", "default-pinhole", "cone-focus"] {
        let s = embedded(name, Some((160, 120)));
        for filter in [FilterKind::Box, FilterKind::Tent, FilterKind::Gaussian] {
            for n in [1u32, 2, 4, 8] {
                for preset in ["linear12", "log8-potentiate", "log8-logadd"] {
                    let h = hw(preset, |h| {
                        h.accumulate.filter = filter;
                        h.raster.samples = n;
                        h.accumulate.weight_bits =
                            h.accumulate.weight_bits.max(2 * n.trailing_zeros());
                    });
                    assert_same_as_reference(&s, &h, &format!("{name} {preset} {filter:?} n={n}"));
                }
            }
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(48))]

    /// Random small scenes (overlapping triangles and light points), every filter and sample
    /// count, frame formats and overflow modes: the fast kernel equals the reference.
    #[test]
    fn fast_kernel_matches_the_reference_on_random_scenes(
        tris in prop::collection::vec((0.0f64..24.0, 0.0f64..24.0, 0.0f64..24.0, 0.0f64..24.0,
            0.0f64..24.0, 0.0f64..24.0, 0.05f64..0.95, 0.0f64..1.0), 1..12),
        pts in prop::collection::vec((0.0f64..24.0, 0.0f64..24.0, 0.05f64..1.0, 0.1f64..3.0), 0..4),
        filter in 0usize..3, n_log in 0u32..4, frac in 0u32..16, wb in 0u32..10,
        overflow in 0usize..5, bg in 0.0f64..0.5,
    ) {
        let mut objects = String::new();
        for (k, t) in tris.iter().enumerate() {
            let z = 0.2 + 0.05 * k as f64;
            objects += &tri([[t.0, t.1, z], [t.2, t.3, z + 0.1], [t.4, t.5, z]], [t.6, t.7, t.6]);
        }
        for p in &pts {
            objects += &point(p.0, p.1, 0.1, p.2, p.3);
        }
        let s = scene(24, 24, bg, &objects);
        let n = 1u32 << n_log;
        let h = hw("linear12", |h| {
            h.accumulate.filter = [FilterKind::Box, FilterKind::Tent, FilterKind::Gaussian][filter];
            h.raster.samples = n;
            h.accumulate.weight_bits = 2 * n_log + wb.min(16 - 2 * n_log);
            h.accumulate.frame.format = QFormat::new(false, 12, frac);
            h.accumulate.frame.overflow = Overflow::ALL[overflow];
        });
        assert_same_as_reference(&s, &h, "random scene");
    }
}
