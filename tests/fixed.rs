//! Tests of `igemu::fixed`: exhaustive comparison with an independent exact rational oracle,
//! exact `f64` input, agreement with the `fixed` crate, properties, instrumentation, parsing.

use igemu::fixed::{
    Overflow, QFormat, Quant, Quantized, Quantizer, SignalStats, quantize_slice_f64,
};
use proptest::prelude::*;

// ---------------------------------------------------------------------------------------------
// Independent oracle: exact rationals num / 2^den_exp with i128 (no use of round_shift).

/// Rounds num / 2^den_exp (den_exp may be negative: then the value is num * 2^-den_exp).
fn oracle_round(num: i128, den_exp: i32, q: Quant) -> i128 {
    if den_exp <= 0 {
        return num.checked_mul(1i128 << (-den_exp)).expect("oracle range");
    }
    let den = 1i128 << den_exp;
    let fl = num.div_euclid(den);
    let r = num.rem_euclid(den);
    if r == 0 {
        return fl;
    }
    let neg = num < 0;
    let tie = 2 * r == den;
    let nearest = if 2 * r < den { fl } else { fl + 1 };
    match q {
        Quant::Trn => fl,
        Quant::TrnZero => {
            if neg {
                fl + 1
            } else {
                fl
            }
        }
        _ if !tie => nearest,
        Quant::Rnd => fl + 1,
        Quant::RndZero => {
            if neg {
                fl + 1
            } else {
                fl
            }
        }
        Quant::RndInf => {
            if neg {
                fl
            } else {
                fl + 1
            }
        }
        Quant::RndMinInf => fl,
        Quant::RndConv => {
            if fl.rem_euclid(2) == 0 {
                fl
            } else {
                fl + 1
            }
        }
    }
}

fn range(signed: bool, w: u32) -> (i128, i128) {
    if signed {
        (-(1i128 << (w - 1)), (1i128 << (w - 1)) - 1)
    } else {
        (0, (1i128 << w) - 1)
    }
}

fn oracle_overflow(v: i128, signed: bool, w: u32, o: Overflow) -> Quantized {
    let (lo, hi) = range(signed, w);
    let q = |code: i128, overflow: bool| Quantized {
        code: code as i64,
        overflow,
    };
    if o == Overflow::SatSym && signed && v == lo {
        // ac_fixed: the exact -2^(W-1) is an underflow under AC_SAT_SYM.
        return q(-hi, true);
    }
    if (lo..=hi).contains(&v) {
        return q(v, false);
    }
    match o {
        Overflow::Wrap => {
            let m = 1i128 << w;
            let mut r = v.rem_euclid(m);
            if signed && r >= m / 2 {
                r -= m;
            }
            q(r, true)
        }
        Overflow::Sat | Overflow::Error => q(v.clamp(lo, hi), true),
        Overflow::SatZero => q(0, true),
        Overflow::SatSym => {
            if v > hi {
                q(hi, true)
            } else if signed {
                q(-hi, true)
            } else {
                q(0, true)
            }
        }
    }
}

/// Every format with total width 1..=max_w.
fn formats(max_w: u32) -> Vec<QFormat> {
    let mut v = Vec::new();
    for w in 1..=max_w {
        for signed in [false, true] {
            for int in u32::from(signed)..=w {
                v.push(QFormat::new(signed, int, w - int));
            }
        }
    }
    v
}

/// Runs `f` over chunks of `items` on all cores.
fn par_for_each<T: Sync>(items: &[T], f: impl Fn(&T) + Sync) {
    let n = std::thread::available_parallelism().map_or(4, |n| n.get());
    let chunk = items.len().div_ceil(n).max(1);
    std::thread::scope(|s| {
        for c in items.chunks(chunk) {
            let f = &f;
            s.spawn(move || c.iter().for_each(f));
        }
    });
}

// ---------------------------------------------------------------------------------------------
// 1. Exhaustive quantize_raw against the oracle.

#[test]
fn quantize_raw_exhaustive_against_oracle() {
    let fmts = formats(10);
    par_for_each(&fmts, |&f| {
        let w = f.total_bits();
        // Source: 3 more fraction bits, 2 more integer bits, both signs (and one spare bit).
        let src_frac = f.frac_bits as i32 + 3;
        let lim = 1i128 << (w + 5);
        for q in Quant::ALL {
            for raw in -lim..lim {
                let r = oracle_round(raw, 3, q);
                for o in Overflow::ALL {
                    let got = Quantizer::new(f, q, o).quantize_raw(raw, src_frac);
                    let want = oracle_overflow(r, f.signed, w, o);
                    if got != want {
                        panic!("{f} {q} {o} raw {raw}/2^{src_frac}: got {got:?}, want {want:?}");
                    }
                }
            }
        }
    });
}

#[test]
fn quantize_raw_other_binary_points() {
    // Shifts from -4 (left shift) to +12, small formats.
    let fmts = formats(6);
    par_for_each(&fmts, |&f| {
        let w = f.total_bits();
        for d in -4i32..=12 {
            let raw_frac = f.frac_bits as i32 + d;
            let lim = 1i128 << (w + 4);
            for q in Quant::ALL {
                for raw in -lim..lim {
                    let r = oracle_round(raw, d, q);
                    for o in Overflow::ALL {
                        let got = Quantizer::new(f, q, o).quantize_raw(raw, raw_frac);
                        let want = oracle_overflow(r, f.signed, w, o);
                        assert_eq!(got, want, "{f} {q} {o} raw {raw}/2^{raw_frac}");
                    }
                }
            }
        }
    });
}

#[test]
fn quantize_raw_huge_left_shifts() {
    let f = QFormat::new(true, 8, 8);
    for o in Overflow::ALL {
        let qz = Quantizer::new(f, Quant::Rnd, o);
        for k in [20, 100, 119, 120, 121, 126, 127, 128, 200, 1000] {
            for raw in [1i128, -1, 3, -3, 255, i128::MAX >> 4, i128::MIN >> 4] {
                let got = qz.quantize_raw(raw, -k);
                assert!(got.overflow, "{o} {raw} << {k}");
                let want = match o {
                    // low 16 bits of raw * 2^(k+8) are zero for k >= 8
                    Overflow::Wrap | Overflow::SatZero => 0,
                    Overflow::Sat | Overflow::Error => {
                        if raw > 0 {
                            32767
                        } else {
                            -32768
                        }
                    }
                    Overflow::SatSym => {
                        if raw > 0 {
                            32767
                        } else {
                            -32767
                        }
                    }
                };
                assert_eq!(got.code, want, "{o} {raw} << {k}");
            }
        }
    }
    // Wrap keeps low bits exactly when the shifted value leaves i128 only slightly.
    let qz = Quantizer::new(QFormat::new(true, 32, 0), Quant::Trn, Overflow::Wrap);
    let raw = 0x1234_5678_9abc_def1i128;
    for k in 60..=127 {
        let want = (raw.wrapping_shl(k as u32) as u128 as u32) as i32 as i64;
        assert_eq!(qz.quantize_raw(raw, -k).code, want, "k {k}");
    }
}

// ---------------------------------------------------------------------------------------------
// 2. quantize_f64.

/// Exact (mantissa, exponent) of a finite f64, independently of the library.
fn f64_parts(x: f64) -> (i128, i32) {
    let b = x.to_bits();
    let e = ((b >> 52) & 0x7ff) as i32;
    let m = (b & ((1 << 52) - 1)) as i128;
    let (m, e) = if e == 0 {
        (m, -1074)
    } else {
        (m | (1 << 52), e - 1075)
    };
    (if b >> 63 == 1 { -m } else { m }, e)
}

fn next_up(x: f64) -> f64 {
    if x == 0.0 {
        return f64::from_bits(1);
    }
    let b = x.to_bits();
    f64::from_bits(if x > 0.0 { b + 1 } else { b - 1 })
}

fn next_down(x: f64) -> f64 {
    -next_up(-x)
}

/// Oracle for any f64 (including tiny, huge and infinite values).
fn oracle_f64(x: f64, f: QFormat, q: Quant, o: Overflow) -> Quantized {
    let w = f.total_bits();
    if x.is_nan() {
        return Quantized {
            code: 0,
            overflow: true,
        };
    }
    let (lo, hi) = range(f.signed, w);
    let far = |pos: bool| {
        let v = if pos { hi + (1 << 40) } else { lo - (1 << 40) };
        oracle_overflow(v, f.signed, w, o)
    };
    if x.is_infinite() {
        // WRAP of +-inf: 0, the limit of huge values (all multiples of 2^W).
        let mut r = far(x > 0.0);
        if o == Overflow::Wrap {
            r.code = 0;
        }
        return r;
    }
    let (m, e) = f64_parts(x);
    let den_exp = -e - f.frac_bits as i32;
    if den_exp < -60 {
        // |value| >= 2^60 LSBs: out of range; WRAP keeps (m * 2^k) mod 2^W.
        let mut r = far(x > 0.0);
        if o == Overflow::Wrap {
            let k = -den_exp;
            let res = if k >= 64 {
                0
            } else {
                (m << k).rem_euclid(1 << w)
            };
            let res = if f.signed && res >= 1 << (w - 1) {
                res - (1 << w)
            } else {
                res
            };
            r.code = res as i64;
        }
        return r;
    }
    let rounded = if m == 0 {
        0
    } else if den_exp > 120 {
        // |value| < 2^53 * 2^-121 < 1/2: only the sign matters.
        match (q, m < 0) {
            (Quant::Trn, true) => -1,
            _ => 0,
        }
    } else {
        oracle_round(m, den_exp, q)
    };
    oracle_overflow(rounded, f.signed, w, o)
}

#[test]
fn quantize_f64_exhaustive_against_oracle() {
    let fmts = formats(10);
    par_for_each(&fmts, |&f| {
        let w = f.total_bits();
        let src_frac = f.frac_bits as i32 + 3;
        let scale = 2f64.powi(-src_frac);
        let lim = 1i128 << (w + 5);
        for q in Quant::ALL {
            for raw in -lim..lim {
                let x = raw as f64 * scale; // exact
                let r = oracle_round(raw, 3, q);
                for o in Overflow::ALL {
                    let got = Quantizer::new(f, q, o).quantize_f64(x);
                    let want = oracle_overflow(r, f.signed, w, o);
                    if got != want {
                        panic!("{f} {q} {o} x {x:e}: got {got:?}, want {want:?}");
                    }
                }
            }
        }
    });
}

#[test]
fn quantize_f64_hard_cases() {
    let fmts = [
        "Q4.4", "UQ4.4", "Q1.7", "UQ0.8", "Q1.0", "UQ1.0", "Q8.0", "Q16.16", "UQ32.0", "Q32.0",
        "Q1.31", "UQ0.32",
    ];
    for fs in fmts {
        let f = QFormat::parse(fs).unwrap();
        let lsb = f.lsb();
        let mut xs = vec![
            0.0,
            -0.0,
            f64::from_bits(1),
            -f64::from_bits(1),
            f64::from_bits((1 << 52) - 1),
            f64::MIN_POSITIVE,
            -f64::MIN_POSITIVE,
            2f64.powi(-200),
            -2f64.powi(-200),
            2f64.powi(-101),
            -2f64.powi(-99),
            f64::MAX,
            f64::MIN,
            f64::INFINITY,
            f64::NEG_INFINITY,
            2f64.powi(99),
            3.0 * 2f64.powi(70),
            -(2f64.powi(53) - 1.0) * 2f64.powi(20),
            -2f64.powi(60),
        ];
        // Exact ties at every LSB across the range and beyond, and their neighbours.
        let (lo, hi) = (f.min_code() as f64, f.max_code() as f64);
        let mut ties: Vec<f64> = (-20..20).map(|k| (f64::from(k) + 0.5) * lsb).collect();
        ties.extend([
            (hi + 0.5) * lsb,
            (lo - 0.5) * lsb,
            (hi - 0.5) * lsb,
            (lo + 0.5) * lsb,
        ]);
        ties.extend([hi * lsb, lo * lsb, (hi + 1.0) * lsb, (lo - 1.0) * lsb]);
        for t in ties {
            xs.extend([t, next_up(t), next_down(t), -t]);
        }
        for &x in &xs {
            for q in Quant::ALL {
                for o in Overflow::ALL {
                    let got = Quantizer::new(f, q, o).quantize_f64(x);
                    let want = oracle_f64(x, f, q, o);
                    assert_eq!(got, want, "{f} {q} {o} x {x:e}");
                }
            }
        }
    }
    // Spot checks written out by hand.
    let q44 = QFormat::new(true, 4, 4);
    let z = |q, o, x| Quantizer::new(q44, q, o).quantize_f64(x);
    let ok = |code| Quantized {
        code,
        overflow: false,
    };
    assert_eq!(z(Quant::RndConv, Overflow::Sat, 2.5 / 16.0), ok(2));
    assert_eq!(z(Quant::RndConv, Overflow::Sat, 3.5 / 16.0), ok(4));
    assert_eq!(z(Quant::Rnd, Overflow::Sat, -2.5 / 16.0), ok(-2));
    assert_eq!(z(Quant::RndInf, Overflow::Sat, -2.5 / 16.0), ok(-3));
    assert_eq!(
        z(Quant::RndZero, Overflow::Sat, next_down(-2.5 / 16.0)),
        ok(-3)
    );
    assert_eq!(z(Quant::Trn, Overflow::Sat, -f64::from_bits(1)), ok(-1));
    assert_eq!(z(Quant::TrnZero, Overflow::Sat, -f64::from_bits(1)), ok(0));
    assert_eq!(z(Quant::Trn, Overflow::Sat, -0.0), ok(0));
    assert_eq!(
        z(Quant::Trn, Overflow::Sat, f64::NAN),
        Quantized {
            code: 0,
            overflow: true
        }
    );
    assert_eq!(
        z(Quant::Trn, Overflow::SatSym, f64::NEG_INFINITY),
        Quantized {
            code: -127,
            overflow: true
        }
    );
    // Unsigned: a tiny negative value floors to -1, which underflows.
    let u = Quantizer::new(QFormat::new(false, 4, 4), Quant::Trn, Overflow::Wrap);
    assert_eq!(
        u.quantize_f64(-2f64.powi(-200)),
        Quantized {
            code: 255,
            overflow: true
        }
    );
}

// ---------------------------------------------------------------------------------------------
// 3. Agreement with the `fixed` crate where the formats coincide.

use igemu::rng::Rng;

/// f64 inputs for a format: a fine grid (all ties of the format and beyond its range),
/// plus seeded random doubles of every magnitude up to 2^(int_bits + 4).
fn f64_inputs(f: QFormat) -> Vec<f64> {
    let mut v = Vec::new();
    let step = f.lsb() / 8.0;
    let span = 1i64 << (f.total_bits() + 5);
    for k in -span..span {
        v.push(k as f64 * step);
    }
    let mut rng = Rng::new(0x9e37_79b9_7f4a_7c15);
    let top = f.int_bits as i32 + 4;
    for _ in 0..200_000 {
        let m = (rng.next_u64() >> 11) as f64 / (1u64 << 53) as f64;
        let e = (rng.next_u64() % 64) as i32 - 60 + top;
        let s = if rng.next_u64() & 1 == 0 { 1.0 } else { -1.0 };
        v.push(s * m * 2f64.powi(e.min(top)));
    }
    v
}

macro_rules! check_fixed_from_f64 {
    ($ty:ty, $fmt:expr, $bits:ty) => {{
        let f = QFormat::parse($fmt).unwrap();
        let sat = Quantizer::new(f, Quant::RndConv, Overflow::Sat);
        let wrap = Quantizer::new(f, Quant::RndConv, Overflow::Wrap);
        for x in f64_inputs(f) {
            let s = <$ty>::saturating_from_num(x).to_bits() as i64;
            assert_eq!(sat.quantize_f64(x).code, s, "{} saturating {x:e}", $fmt);
            let w = <$ty>::wrapping_from_num(x).to_bits() as i64;
            assert_eq!(wrap.quantize_f64(x).code, w, "{} wrapping {x:e}", $fmt);
        }
    }};
}

#[test]
fn agrees_with_fixed_crate_from_f64() {
    use fixed::types::{I1F15, I4F4, U4F12, U8F0};
    check_fixed_from_f64!(I4F4, "Q4.4", i8);
    check_fixed_from_f64!(U8F0, "UQ8.0", u8);
    check_fixed_from_f64!(I1F15, "Q1.15", i16);
    check_fixed_from_f64!(U4F12, "UQ4.12", u16);
}

macro_rules! check_fixed_from_i8f8 {
    ($ty:ty, $fmt:expr) => {{
        use fixed::types::I8F8;
        let f = QFormat::parse($fmt).unwrap();
        let sat = Quantizer::new(f, Quant::Trn, Overflow::Sat);
        let wrap = Quantizer::new(f, Quant::Trn, Overflow::Wrap);
        for b in i16::MIN..=i16::MAX {
            let x = I8F8::from_bits(b);
            let s = x.saturating_to_num::<$ty>().to_bits() as i64;
            assert_eq!(
                sat.quantize_raw(i128::from(b), 8).code,
                s,
                "{} sat {x}",
                $fmt
            );
            let w = x.wrapping_to_num::<$ty>().to_bits() as i64;
            assert_eq!(
                wrap.quantize_raw(i128::from(b), 8).code,
                w,
                "{} wrap {x}",
                $fmt
            );
        }
    }};
}

#[test]
fn agrees_with_fixed_crate_fixed_to_fixed() {
    use fixed::types::{I1F15, I4F4, U4F12, U8F0};
    check_fixed_from_i8f8!(I4F4, "Q4.4");
    check_fixed_from_i8f8!(U8F0, "UQ8.0");
    check_fixed_from_i8f8!(I1F15, "Q1.15");
    check_fixed_from_i8f8!(U4F12, "UQ4.12");
}

// ---------------------------------------------------------------------------------------------
// 4. Properties.

fn any_format() -> impl Strategy<Value = QFormat> {
    (any::<bool>(), 1u32..=32, 0u32..=32).prop_map(|(signed, w, i)| {
        let lo = u32::from(signed);
        let int = lo + i % (w + 1 - lo);
        QFormat::new(signed, int, w - int)
    })
}

fn any_quant() -> impl Strategy<Value = Quant> {
    (0usize..7).prop_map(|i| Quant::ALL[i])
}

fn any_overflow() -> impl Strategy<Value = Overflow> {
    (0usize..5).prop_map(|i| Overflow::ALL[i])
}

const SAFE: i128 = 1 << 100;

proptest! {
    #![proptest_config(ProptestConfig::with_cases(4000))]

    #[test]
    fn never_panics_and_stays_canonical(
        f in any_format(), q in any_quant(), o in any_overflow(),
        raw in -SAFE..SAFE, raw_frac in -200i32..300,
    ) {
        let r = Quantizer::new(f, q, o).quantize_raw(raw, raw_frac);
        prop_assert!(r.code >= f.min_code() && r.code <= f.max_code(), "{r:?}");
        if o == Overflow::SatSym && f.signed {
            prop_assert!(r.code >= -f.max_code());
        }
    }

    #[test]
    fn sat_is_monotone(
        f in any_format(), q in any_quant(),
        a in -SAFE..SAFE, b in -SAFE..SAFE, raw_frac in -40i32..140,
    ) {
        let (a, b) = if a <= b { (a, b) } else { (b, a) };
        for o in [Overflow::Sat, Overflow::SatSym, Overflow::Error] {
            let z = Quantizer::new(f, q, o);
            prop_assert!(z.quantize_raw(a, raw_frac).code <= z.quantize_raw(b, raw_frac).code);
        }
    }

    #[test]
    fn rnd_conv_error_at_most_half_lsb(
        f in any_format(), raw in -SAFE..SAFE, d in -20i32..90,
    ) {
        let z = Quantizer::new(f, Quant::RndConv, Overflow::Sat);
        let raw_frac = f.frac_bits as i32 + d;
        let r = z.quantize_raw(raw, raw_frac);
        if !r.overflow {
            if d >= 0 {
                // |code * 2^d - raw| <= 2^d / 2
                let err = (i128::from(r.code) << d) - raw;
                prop_assert!(2 * err.abs() <= 1i128 << d, "err {err} d {d}");
            } else {
                prop_assert_eq!(i128::from(r.code), raw << (-d));
            }
        }
    }

    #[test]
    fn f64_path_equals_integer_path(
        f in any_format(), q in any_quant(), o in any_overflow(),
        m in -(1i64 << 53)..(1i64 << 53), e in -1074i32..900,
    ) {
        let x = m as f64 * 2f64.powi(e.max(-1022)) ;
        prop_assume!(x.is_finite());
        let (mm, ee) = f64_parts(x);
        let z = Quantizer::new(f, q, o);
        prop_assert_eq!(z.quantize_f64(x), z.quantize_raw(mm, -ee));
    }
}

// ---------------------------------------------------------------------------------------------
// 5. SignalStats.

#[test]
fn signal_stats_known_sequence() {
    let f = QFormat::new(true, 4, 4);
    let mut s = SignalStats::new("test.sig", f);
    s.record(0.25, 0, false); // err -0.25
    s.record(1.5, 2, false); // err 0.5
    s.record(-3.0, -3, false); // err 0
    s.record(200.0, 200, true); // err 0, overflow
    assert_eq!(s.count, 4);
    assert_eq!((s.min, s.max), (Some(-3), Some(200)));
    assert_eq!(s.overflows, 1);
    assert_eq!(s.err_sum, 0.25);
    assert_eq!(s.err_sq_sum, 0.3125);
    assert_eq!(s.mean_error(), 0.0625);
    assert_eq!(s.rms_error(), (0.3125f64 / 4.0).sqrt());
    // [-3, 200] LSBs needs 9 bits signed: Q5.4.
    assert_eq!(s.proposed_format(), Some(QFormat::new(true, 5, 4)));
    s.record_code(-300);
    s.add_overflows(2);
    assert_eq!((s.count, s.min, s.overflows), (5, Some(-300), 3));
    assert_eq!(s.proposed_format(), Some(QFormat::new(true, 6, 4)));

    let j = serde_json::to_value(&s).unwrap();
    assert_eq!(j["format"], "Q4.4");
    assert_eq!(j["name"], "test.sig");

    let empty = SignalStats::new("e", f);
    assert_eq!(empty.proposed_format(), None);
    assert_eq!((empty.rms_error(), empty.mean_error()), (0.0, 0.0));
}

#[test]
fn proposed_formats_on_known_ranges() {
    let prop = |f: &str, lo: i128, hi: i128| {
        let mut s = SignalStats::new("p", QFormat::parse(f).unwrap());
        s.record_code(lo);
        s.record_code(hi);
        s.proposed_format().unwrap().to_string()
    };
    assert_eq!(prop("UQ12.0", 0, 4095), "UQ12.0");
    assert_eq!(prop("UQ12.0", 0, 4096), "UQ13.0");
    assert_eq!(prop("UQ12.0", 3, 200), "UQ8.0");
    assert_eq!(prop("UQ0.24", 0, 1 << 24), "UQ1.24");
    assert_eq!(prop("UQ0.24", 0, 5), "UQ0.24");
    assert_eq!(prop("Q4.12", -32768, 32767), "Q4.12");
    assert_eq!(prop("Q4.12", -32769, 0), "Q5.12");
    assert_eq!(prop("Q4.12", -1, 0), "Q1.12");
    assert_eq!(prop("Q8.0", -128, 127), "Q8.0");
    assert_eq!(prop("Q8.0", -129, 127), "Q9.0");
    assert_eq!(prop("Q8.0", 0, 0), "Q1.0");
    // Unsigned signal that went negative: a signed proposal.
    assert_eq!(prop("UQ8.0", -1, 255), "Q9.0");
    // Wider than a signal format: proposed anyway, and it does not validate.
    let wide = QFormat::parse(&prop("Q16.16", -(1 << 40), 0)).unwrap_err();
    assert!(wide.contains("1..=32"), "{wide}");
}

#[test]
fn stats_merge_and_slice_helper() {
    let f = QFormat::new(false, 4, 4);
    let z = Quantizer::new(f, Quant::RndConv, Overflow::Sat);
    let xs: Vec<f64> = (-40..400).map(|k| f64::from(k) * 0.013).collect();
    let mut out = vec![0i64; xs.len()];
    let mut whole = SignalStats::new("s", f);
    quantize_slice_f64(&z, &xs, &mut out, &mut whole);
    for (x, c) in xs.iter().zip(&out) {
        assert_eq!(*c, z.quantize_f64(*x).code);
    }
    assert_eq!(whole.count, xs.len() as u64);
    // k = -3..=-40 round below 0 and saturate (k = -1, -2 round to 0); 0.013*399 = 5.187 fits.
    assert_eq!(whole.overflows, 38);
    assert_eq!(whole.min, Some(-8)); // -0.52 * 16 = -8.32 -> -8
    assert_eq!(whole.max, Some(83)); // 5.187 * 16 = 82.992 -> 83
    assert!(whole.rms_error() <= 0.5 && whole.rms_error() > 0.2);

    let (a, b) = xs.split_at(123);
    let mut sa = SignalStats::new("s", f);
    let mut sb = SignalStats::new("s", f);
    quantize_slice_f64(&z, a, &mut out[..123], &mut sa);
    quantize_slice_f64(&z, b, &mut out[123..], &mut sb);
    let mut m1 = sa.clone();
    m1.merge(&sb);
    let mut m2 = sb.clone();
    m2.merge(&sa);
    for m in [&m1, &m2] {
        assert_eq!(
            (m.count, m.min, m.max, m.overflows),
            (whole.count, whole.min, whole.max, whole.overflows)
        );
        assert!((m.err_sq_sum - whole.err_sq_sum).abs() < 1e-9);
        assert!((m.err_sum - whole.err_sum).abs() < 1e-9);
    }
    let mut e = SignalStats::new("s", f);
    e.merge(&SignalStats::new("s", f));
    assert_eq!((e.min, e.max), (None, None));
    e.merge(&sa);
    assert_eq!((e.min, e.max), (sa.min, sa.max));

    // Non-finite inputs: counted as overflows, range untouched.
    let mut s = SignalStats::new("nan", f);
    let mut o = [7i64; 3];
    quantize_slice_f64(&z, &[f64::NAN, f64::INFINITY, 1.0], &mut o, &mut s);
    assert_eq!(o, [0, 255, 16]);
    assert_eq!(
        (s.count, s.overflows, s.min, s.max),
        (3, 2, Some(16), Some(16))
    );
}

// ---------------------------------------------------------------------------------------------
// 6. Parsing and display.

#[test]
fn qformat_parse_display_round_trip() {
    for f in formats(32) {
        let s = f.to_string();
        assert_eq!(QFormat::parse(&s).unwrap(), f, "{s}");
        assert_eq!(QFormat::parse(&s.to_lowercase()).unwrap(), f, "{s}");
        let j = serde_json::to_string(&f).unwrap();
        assert_eq!(j, format!("\"{s}\""));
        assert_eq!(serde_json::from_str::<QFormat>(&j).unwrap(), f);
    }
    assert_eq!(
        QFormat::parse("uq0.24").unwrap(),
        QFormat::new(false, 0, 24)
    );
    assert_eq!(QFormat::parse("Q4.12").unwrap(), QFormat::new(true, 4, 12));
    assert_eq!(
        QFormat::parse("UQ12.0").unwrap(),
        QFormat::new(false, 12, 0)
    );
    let z = Quantizer::new(QFormat::new(true, 4, 12), Quant::RndConv, Overflow::SatSym);
    let j = serde_json::to_string(&z).unwrap();
    assert_eq!(
        j,
        r#"{"format":"Q4.12","quant":"RND_CONV","overflow":"SAT_SYM"}"#
    );
    assert_eq!(serde_json::from_str::<Quantizer>(&j).unwrap(), z);
}

#[test]
fn qformat_bad_strings() {
    let e = QFormat::parse("Q0.4").unwrap_err();
    assert!(e.contains("int_bits >= 1") && e.contains("sign bit"), "{e}");
    let e = QFormat::parse("UQ40.0").unwrap_err();
    assert!(e.contains("total width 40 bits is outside 1..=32"), "{e}");
    for bad in [
        "Q4", "X4.4", "", "Q", "Q.4", "Q4.", "Q+4.4", "Q4.-1", "UQ 4.4", "Q4.4.4", "QQ4.4",
    ] {
        let e = QFormat::parse(bad).unwrap_err();
        assert!(
            e.contains("expected Q<int>.<frac>") && e.contains("UQ<int>.<frac>"),
            "{bad}: {e}"
        );
    }
    let e = QFormat::parse("UQ0.0").unwrap_err();
    assert!(e.contains("1..=32"), "{e}");
    let e = QFormat::parse("Q99999999999.1").unwrap_err();
    assert!(e.contains("expected"), "{e}");
    assert!(
        serde_json::from_str::<QFormat>("\"Q40.0\"")
            .unwrap_err()
            .to_string()
            .contains("1..=32")
    );
    assert!(QFormat::new(true, 0, 8).validate().is_err());
    assert!(QFormat::new(false, 0, 32).validate().is_ok());
    assert!(QFormat::new(false, u32::MAX, 2).validate().is_err());
}

/// `RoundShift::raw_range` is the range of raw values whose rounding lies in the codes
/// asked for, for every mode (brute force over small values and shifts).
#[test]
fn raw_range_holds_exactly_the_values_that_round_into_range() {
    use igemu::fixed::{Quant, RoundShift};
    for q in Quant::ALL {
        for shift in 0..6u32 {
            let r = RoundShift::new(shift, q);
            for (lo, hi) in [(0, 0), (0, 5), (-3, 2), (4, 3), (-2, -1), (7, 40)] {
                let got = r.raw_range(lo, hi);
                let inside = |v: i64| (lo..=hi).contains(&r.apply(v));
                let want: Vec<i64> = (-2000i64..2000).filter(|&v| inside(v)).collect();
                match got {
                    None => assert!(want.is_empty(), "{q} {shift} {lo}..={hi}"),
                    Some((a, b)) => {
                        assert!(inside(a) && inside(b), "{q} {shift} {lo}..={hi}: ends");
                        assert!(!inside(a - 1) && !inside(b + 1), "{q} {shift}: widest");
                        assert_eq!(
                            want,
                            (a..=b).filter(|&v| v.abs() < 2000).collect::<Vec<_>>()
                        );
                    }
                }
            }
        }
    }
    // Ranges that reach the edges of the small values.
    let r = RoundShift::new(4, Quant::RndConv);
    assert_eq!(r.raw_range(i64::MIN, i64::MAX), Some((-(1 << 62), 1 << 62)));
    assert_eq!(r.raw_range(1 << 60, i64::MAX), None);
}

/// The i64 fast path (and its non-negative u64 form) rounds exactly like the i128
/// reference, for every mode.
#[test]
fn round_shift_i64_equals_round_shift() {
    use igemu::fixed::{Quant, RoundShift, round_shift, round_shift_i64};
    for q in Quant::ALL {
        for shift in 0..12u32 {
            for raw in -5000i64..5000 {
                assert_eq!(
                    round_shift_i64(raw, shift, q) as i128,
                    round_shift(raw as i128, shift, q),
                    "{q} {shift} {raw}"
                );
                if raw >= 0 {
                    assert_eq!(
                        RoundShift::new(shift, q).apply_nonneg(raw as u64) as i128,
                        round_shift(raw as i128, shift, q),
                        "{q} {shift} {raw} in u64"
                    );
                }
            }
        }
        for shift in [0u32, 1, 20, 40, 61, 62] {
            for raw in [(1u64 << 62) - 1, 1 << 62, (1 << 40) + (1 << 39), 3 << 20] {
                assert_eq!(
                    RoundShift::new(shift, q).apply_nonneg(raw) as i128,
                    round_shift(raw as i128, shift, q),
                    "{q} {shift} {raw} in u64"
                );
            }
        }
        for raw in [
            i64::MIN / 4,
            i64::MAX / 4,
            // Sums that leave i64 take the i128 path.
            i64::MIN,
            i64::MIN + 1,
            i64::MAX,
            i64::MAX - 1,
            -(1 << 40) - 1,
            (1 << 40) + (1 << 19),
        ] {
            for shift in [1u32, 20, 40, 61, 62] {
                assert_eq!(
                    round_shift_i64(raw, shift, q) as i128,
                    round_shift(raw as i128, shift, q)
                );
            }
        }
    }
}
