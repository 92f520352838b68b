//! The gamma LUT fused into an ordered dither's pass (the gamma stage leaves its codes as a
//! `PixelTap::deferred` LUT read, the dither looks them up row by row: `dither::Input::Lut`)
//! against the two stages run apart (the LUT's plane looked up, then dithered): the same
//! DAC codes, saturation counts and stage reports on the default scene and a ramp, over
//! DAC widths, dither fraction bits, masks and frame codings; and the kernel on random
//! frames, LUTs and shapes (proptest), on every run mode and thread count.

mod common;

use common::{scene, tri};
use igemu::config::{DitherKind, HwConfig};
use igemu::pipeline::fast::emulate;
use igemu::pipeline::render;
use igemu::scene::Scene;
use igemu::stage::dither::{Dither, Input, Mask, Run, apply_ordered_from, apply_ordered_with};
use igemu::stage::gamma::lookup;
use igemu::stage::{RunOptions, StageId, StageReport};
use proptest::prelude::*;
use std::sync::OnceLock;

/// A full-screen horizontal intensity ramp from black to white (a slow ramp is where the
/// dither's fraction bits matter).
fn ramp() -> Scene {
    let (w, h) = (160.0, 60.0);
    let objs = tri(
        [[0.0, 0.0, 0.5], [w, 0.0, 0.5], [0.0, h, 0.5]],
        [0.0, 1.0, 0.0],
    ) + &tri([[w, 0.0, 0.5], [w, h, 0.5], [0.0, h, 0.5]], [1.0, 1.0, 0.0]);
    scene(160, 60, 0.0, &objs)
}

fn small_default() -> Scene {
    let mut s = Scene::embedded("default").expect("embedded");
    s.image.width = 200;
    s.image.height = 150;
    s
}

/// Work, signals (range and overflows) and notes of a stage report.
fn facts(s: &StageReport) -> String {
    let sig: Vec<_> = s
        .signals
        .iter()
        .map(|x| (x.name.clone(), x.min, x.max, x.overflows))
        .collect();
    format!("{:?} {sig:?} {:?}", s.work, s.notes)
}

/// Runs `h` on `s` fixed-only (fused) and checks it against the stages run apart: the
/// gamma tap is left deferred, its codes dithered as a plane give the dither's codes and
/// saturations, and a full render (whose stage-local comparison reads the gamma plane
/// before the dither runs, so the dither reads a plane) gives the same codes and reports.
fn check(s: &Scene, h: &HwConfig, what: &str) {
    let e = emulate(s, h, RunOptions::FIXED_ONLY, None).unwrap_or_else(|e| panic!("{what}: {e}"));
    let at = |id| e.steps.iter().position(|x| x.id == id).expect("planned");
    let (gi, di) = (at(StageId::Gamma), at(StageId::Dither));
    assert_eq!(di, gi + 1, "{what}");
    let px = e.steps[gi].outcome.taps.fixed.pixels();
    let lut = px
        .lut()
        .unwrap_or_else(|| panic!("{what}: the gamma tap is deferred"));
    assert!(px.ready().is_none(), "{what}: nothing read the LUT plane");
    // Apart: the LUT's plane, then the dither on it.
    let mut plane = vec![0u32; lut.acc().len()];
    lookup(&lut.table, lut.acc(), lut.shift, &mut plane);
    let (w, ht) = (s.image.width, s.image.height);
    let mut want = vec![0u32; plane.len()];
    let st = Dither::new(&h.dither).apply(&plane, w, ht, px.frac, px.max, &mut want);
    let dither = &e.steps[di].outcome;
    assert_eq!(dither.taps.fixed.pixels().codes(), want, "{what}: codes");
    assert_eq!(dither.report.signals[0].overflows, st.overflows, "{what}");
    // The deferred tap reads as the plane (dumps, a run stopped after gamma).
    assert_eq!(px.codes(), plane, "{what}: the gamma tap's codes");
    let work = &e.steps[gi].outcome.report.work;
    assert_eq!(work["lookups"], plane.len() as u64, "{what}");
    // The full render (stage-local comparisons on: the gamma plane is read first).
    let r = render(s, h, RunOptions::default()).unwrap_or_else(|e| panic!("{what}: {e}"));
    assert!(
        e.channels[0] == r.dac,
        "{what}: DAC codes of the full render"
    );
    assert_eq!(e.report.overflows, r.report.overflows, "{what}");
    for (a, b) in e.report.stages.iter().zip(&r.report.stages) {
        assert_eq!(a.name, b.name, "{what}");
        if a.name == "gamma" || a.name == "dither" {
            assert_eq!(facts(a), facts(b), "{what}: {}", a.name);
        }
    }
}

#[test]
fn fused_equals_apart_on_the_default_scene_and_a_ramp() {
    let scenes = [("default", small_default()), ("ramp", ramp())];
    for (name, s) in &scenes {
        for (dac, f) in [(8, 4), (8, 1), (10, 3), (12, 6), (6, 8)] {
            for kind in [
                DitherKind::Bayer8,
                DitherKind::Bayer2,
                DitherKind::BlueNoise,
            ] {
                let mut h = HwConfig::default_config();
                h.gamma.dac_bits = dac;
                h.dither.kind = kind;
                h.dither.frac_bits = f;
                if h.validate().is_err() {
                    continue;
                }
                check(s, &h, &format!("{name} dac {dac} f {f} {kind:?}"));
            }
        }
    }
}

#[test]
fn fused_equals_apart_on_log_coding_temporal_masks_and_overflow() {
    let s = small_default();
    let mut h = HwConfig::preset("log8-logadd").unwrap();
    h.dither.kind = DitherKind::Bayer4;
    check(&s, &h, "log8-logadd bayer4");
    let mut h = HwConfig::default_config();
    h.dither.kind = DitherKind::Bayer8;
    h.dither.temporal = true;
    h.dither.frame = 5;
    check(&ramp(), &h, "temporal bayer8");
    // A linear LUT.
    let mut h = HwConfig::default_config();
    h.dither.kind = DitherKind::Bayer8;
    h.gamma.correction = false;
    check(&ramp(), &h, "linear LUT");
}

/// The ordered masks (made once: the blue-noise mask takes a while).
fn masks() -> &'static [Mask] {
    static MASKS: OnceLock<Vec<Mask>> = OnceLock::new();
    MASKS.get_or_init(|| {
        let mut d = HwConfig::default_config().dither;
        [
            DitherKind::Bayer2,
            DitherKind::Bayer4,
            DitherKind::Bayer8,
            DitherKind::BlueNoise,
        ]
        .into_iter()
        .filter_map(|k| {
            d.kind = k;
            Mask::of(&d)
        })
        .collect()
    })
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(96))]

    /// The fused kernel gives the lookup-then-dither codes and saturation count on random
    /// frames (addresses past the table's end included), LUTs and shapes, every run mode,
    /// on one and three threads.
    #[test]
    fn fused_kernel_equals_lookup_then_dither(
        width in 1u32..70,
        rows in 1usize..40,
        shift in 0u32..5,
        s in 0u32..9,
        out_bits in 1u32..13,
        addr_bits in 1u32..9,
        seed in any::<u64>(),
        m in 0usize..4,
        frame in 0u32..70,
    ) {
        let mut rng = igemu::rng::Rng::new(seed);
        let n = width as usize * rows;
        let top = 1u64 << (addr_bits + shift + 1);
        let acc: Vec<u32> = (0..n).map(|_| (rng.next_u64() % top) as u32).collect();
        let vmax = 1u64 << (out_bits + s + 1);
        let table: Vec<u32> =
            (0..1usize << addr_bits).map(|_| (rng.next_u64() % vmax) as u32).collect();
        let omax = (1u32 << out_bits) - 1;
        let mask = &masks()[m];
        let mut plane = vec![0u32; n];
        lookup(&table, &acc, shift, &mut plane);
        let mut want = vec![0u32; n];
        let sat = apply_ordered_with(&plane, width, s, omax, mask, frame, &mut want, Run::Serial);
        let input = Input::Lut { acc: &acc, table: &table, shift };
        for threads in [1, 3] {
            let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
            for run in [Run::Parallel, Run::Serial, Run::Portable] {
                let mut out = vec![u32::MAX; n];
                let got = pool.install(|| {
                    apply_ordered_from(input, width, s, omax, mask, frame, &mut out, run)
                });
                prop_assert_eq!(got, sat, "{:?} {} threads", run, threads);
                prop_assert_eq!(&out, &want, "{:?} {} threads", run, threads);
            }
        }
    }
}
