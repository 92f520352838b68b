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
