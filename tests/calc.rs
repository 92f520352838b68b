//! Every number of docs/reference.md §6, to the printed precision, plus error cases.

use igemu::analysis::calc::{
    brightness_error_uncorrected, circle_of_confusion, depth_of_field, gaussian_half_size_factor,
    widths,
};

/// Asserts that `x` printed with `decimals` decimals is `want`.
fn printed(x: f64, decimals: usize, want: &str) {
    assert_eq!(format!("{x:.decimals$}"), want, "value {x}");
}

#[test]
fn intensity_dac_and_log_widths() {
    let w05 = widths(100.0, 0.05, 2.4).unwrap();
    let w02 = widths(100.0, 0.02, 2.4).unwrap();
    // Linear levels N_I = (K - 1) / delta: 1980 / 4950 (11 / 13 bits strictly).
    printed(w05.linear.levels, 0, "1980");
    printed(w02.linear.levels, 0, "4950");
    assert_eq!((w05.linear.bits, w02.linear.bits), (11, 13));
    // 8-bit linear contrast limit 1 + 256 delta: 6.12 (delta 0.02) / 13.8 (delta 0.05).
    printed(w02.linear8_max_contrast, 2, "6.12");
    printed(w05.linear8_max_contrast, 1, "13.8");
    // DAC levels N_U: 165.1 / 412.8 (8 / 9 bits).
    printed(w05.dac.levels, 1, "165.1");
    printed(w02.dac.levels, 1, "412.8");
    assert_eq!((w05.dac.bits, w02.dac.bits), (8, 9));
    // Log grades m: 94.4 / 232.6 (7 / 8 bits).
    printed(w05.log_grades.levels, 1, "94.4");
    printed(w02.log_grades.levels, 1, "232.6");
    assert_eq!((w05.log_grades.bits, w02.log_grades.bits), (7, 8));
    assert_eq!((w05.contrast, w05.weber, w05.gamma), (100.0, 0.05, 2.4));
    let j = serde_json::to_value(&w05).unwrap();
    assert_eq!(j["linear"]["bits"], 11);
}

#[test]
fn levels_bits_at_powers_of_two() {
    // (K - 1) / delta = 256 exactly: 8 bits hold 256 levels; 257 needs 9.
    assert_eq!(widths(65.0, 0.25, 2.2).unwrap().linear.bits, 8);
    assert_eq!(widths(65.25, 0.25, 2.2).unwrap().linear.bits, 9);
}

#[test]
fn brightness_error_and_gaussian_factor() {
    // -62.1 %
    printed(100.0 * brightness_error_uncorrected(2.4, 2), 1, "-62.1");
    assert_eq!(brightness_error_uncorrected(1.0, 3), 0.0);
    assert_eq!(brightness_error_uncorrected(2.4, 1), 0.0);
    assert!(brightness_error_uncorrected(2.4, 0).is_nan());
    printed(gaussian_half_size_factor(0.05), 3, "1.731");
    assert_eq!(gaussian_half_size_factor(1.0), 0.0);
}

#[test]
fn depth_of_field_reference_case() {
    // N = 11, C = 0.035 mm, F = 200 mm, L = 2.5 m.
    let d = depth_of_field(11.0, 0.035, 200.0, 2500.0).unwrap();
    printed(d.front, 2, "58.74");
    printed(d.back, 2, "61.64");
    printed(d.near, 1, "2441.3");
    printed(d.far, 1, "2561.6");
    printed(d.total, 2, "120.38");
    printed(d.hyperfocal, 0, "103896");
    // Beyond the hyperfocal distance the back depth is infinite.
    let far = depth_of_field(11.0, 0.035, 200.0, 200_000.0).unwrap();
    assert_eq!(far.back, f64::INFINITY);
    assert_eq!(far.far, f64::INFINITY);
    assert!(far.front.is_finite() && far.near > 0.0);
}

#[test]
fn circle_of_confusion_values() {
    // F = 50, U = 1050, L = 2100, N = 2: 2500/1000 * 1050 / 4200 = 0.625.
    assert!((circle_of_confusion(50.0, 2.0, 1050.0, 2100.0) - 0.625).abs() < 1e-12);
    assert_eq!(circle_of_confusion(200.0, 11.0, 2500.0, 2500.0), 0.0);
    // Symmetric in |L - U|, larger in front (smaller L).
    let near = circle_of_confusion(200.0, 11.0, 2500.0, 2400.0);
    let far = circle_of_confusion(200.0, 11.0, 2500.0, 2600.0);
    assert!(near > far && far > 0.0);
}

#[test]
fn error_cases_name_parameter_and_range() {
    let e = widths(1.0, 0.05, 2.4).unwrap_err();
    assert!(e.contains("contrast") && e.contains("> 1"), "{e}");
    let e = widths(f64::INFINITY, 0.05, 2.4).unwrap_err();
    assert!(e.contains("contrast"), "{e}");
    for bad in [0.0, 1.0, -0.1, f64::NAN] {
        let e = widths(100.0, bad, 2.4).unwrap_err();
        assert!(e.contains("weber") && e.contains("(0, 1)"), "{e}");
    }
    for bad in [1.0, 0.5, f64::NAN, f64::INFINITY] {
        let e = widths(100.0, 0.05, bad).unwrap_err();
        assert!(
            e.contains("gamma") && e.contains("> 1") && e.contains("eq. 10"),
            "{e}"
        );
    }
    let e = depth_of_field(0.0, 0.035, 200.0, 2500.0).unwrap_err();
    assert!(e.contains("f_number") && e.contains("> 0"), "{e}");
    let e = depth_of_field(11.0, -1.0, 200.0, 2500.0).unwrap_err();
    assert!(e.contains("coc"), "{e}");
    let e = depth_of_field(11.0, 0.035, f64::NAN, 2500.0).unwrap_err();
    assert!(e.contains("focal"), "{e}");
    let e = depth_of_field(11.0, 0.035, 200.0, 150.0).unwrap_err();
    assert!(
        e.contains("distance") && e.contains("greater than the focal length"),
        "{e}"
    );
}
