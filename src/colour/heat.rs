//! The heat map of a per-pixel colour difference, for a PNG or an HTML page.

/// The heat map's scale: `(Delta E_00, RGB8 colour)` stops, the colour interpolated linearly
/// in RGB between neighbouring stops and held at the last one beyond it: 0 black, 1 blue
/// (about one CIEDE2000 just-noticeable difference), [`super::JND`] = 2.3 yellow, 5 and above
/// red. A legend draws these stops.
pub const HEAT_STOPS: [(f32, [u8; 3]); 4] = [
    (0.0, [0, 0, 0]),
    (1.0, [0, 0, 255]),
    (2.3, [255, 255, 0]),
    (5.0, [255, 0, 0]),
];

/// The heat-map colour of one `Delta E_00` (see [`HEAT_STOPS`]); a negative or NaN value is
/// black.
pub fn heat_colour(e: f32) -> [u8; 3] {
    let last = HEAT_STOPS[HEAT_STOPS.len() - 1];
    if e.is_nan() || e <= HEAT_STOPS[0].0 {
        return HEAT_STOPS[0].1;
    }
    if e >= last.0 {
        return last.1;
    }
    let k = HEAT_STOPS.iter().rposition(|s| s.0 <= e).unwrap_or(0);
    let ((e0, c0), (e1, c1)) = (HEAT_STOPS[k], HEAT_STOPS[k + 1]);
    let t = (e - e0) / (e1 - e0);
    [0, 1, 2].map(|i| (f32::from(c0[i]) + t * (f32::from(c1[i]) - f32::from(c0[i]))).round() as u8)
}

/// The RGB8 heat map (row-major, 3 bytes a pixel) of a `width x height` per-pixel
/// `Delta E_00` map such as [`super::DeltaE::map`]. Panics unless `map` holds
/// `width * height` values.
pub fn delta_e_image(map: &[f32], width: u32, height: u32) -> Vec<u8> {
    assert_eq!(
        map.len(),
        width as usize * height as usize,
        "the map holds {} values, not width * height",
        map.len()
    );
    map.iter().flat_map(|&e| heat_colour(e)).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn colour_heat_scale_passes_its_stops() {
        for (e, c) in HEAT_STOPS {
            assert_eq!(heat_colour(e), c, "{e}");
        }
        assert_eq!(heat_colour(0.5), [0, 0, 128]);
        assert_eq!(heat_colour(50.0), [255, 0, 0]);
        assert_eq!(heat_colour(-1.0), [0, 0, 0]);
        assert_eq!(heat_colour(f32::NAN), [0, 0, 0]);
        assert_eq!(
            delta_e_image(&[0.0, 1.0, 2.3, 9.0], 2, 2),
            [0, 0, 0, 0, 0, 255, 255, 255, 0, 255, 0, 0]
        );
    }
}
