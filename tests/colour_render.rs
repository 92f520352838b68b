//! Colour through the pipeline: R, G and B share one raster and one z-buffer and run the
//! stages after visibility once per channel. A grey scene rendered in three channels gives
//! its grey DAC codes in every channel (so the golden hashes of the grey scenes carry over),
//! per-channel word widths reach their channel (with their cost and cycles), a flat colour
//! field is flat in every channel, equal energy holds per channel, a log-coded sample word
//! stores depth and id once, the binary writes an RGB PNG, `ranges` and `hdl vectors` take
//! each channel, and the HTML report shows the render in colour.

mod common;

use igemu::config::{DofKind, HwConfig};
use igemu::files::TomlFile;
use igemu::pipeline::{self, Render};
use igemu::scene::Scene;
use igemu::stage::RunOptions;

fn render(s: &Scene, h: &HwConfig) -> Render {
    pipeline::render(s, h, RunOptions::FAST).unwrap_or_else(|e| panic!("{e}"))
}

fn hw_text(text: &str) -> HwConfig {
    HwConfig::from_toml(&TomlFile::from_text("hw.toml", text)).unwrap_or_else(|e| panic!("{e}"))
}

/// The default scene at a quarter of its size (the same geometry and lens).
fn small_default() -> Scene {
    let mut s = Scene::default_scene();
    s.image.width = 160;
    s.image.height = 120;
    s
}

#[test]
fn a_grey_scene_in_three_channels_gives_its_grey_codes_in_each() {
    // The full-size default scene: its grey codes are the golden ones (tests/golden.rs).
    let grey = Scene::default_scene();
    let mut colour = grey.clone();
    colour.image.colour = true;
    let h = HwConfig::default_config();
    let g = render(&grey, &h);
    assert!(g.colour.is_none(), "a grey scene renders one channel");
    let c = render(&colour, &h);
    let ch = &c.colour.as_ref().expect("three channels").channels;
    assert_eq!(ch.len(), 3);
    for (k, channel) in ch.iter().enumerate() {
        assert!(
            channel.dac == g.dac,
            "channel {k}: fixed codes differ from grey"
        );
        assert!(
            channel.dac_ref == g.dac_ref,
            "channel {k}: float codes differ"
        );
    }
    assert_eq!(c.dac, g.dac, "the report's channel is R");
    // One raster and one z-buffer: the geometry stages ran once.
    let geometry = ["input", "setup", "raster", "visibility"];
    for name in geometry {
        assert_eq!(
            c.steps.iter().filter(|s| s.id.name() == name).count(),
            1,
            "{name}"
        );
    }
    let lanes = &c.colour.as_ref().unwrap().lanes;
    assert_eq!(lanes.len(), 2);
    assert!(
        lanes
            .iter()
            .flatten()
            .all(|s| !geometry.contains(&s.id.name()))
    );
    // The report counts three intensity datapaths: the frame memory three times.
    let frame = |r: &Render| r.report.cycles.cost.storage_bits.get("accumulate").copied();
    assert_eq!(frame(&c), frame(&g).map(|b| 3 * b));
    // One z-buffer in the emulator too: the channels' sample taps share the depth and id
    // planes (not copies), each with its own intensity plane.
    let vis = c
        .taps(igemu::stage::StageId::Visibility)
        .expect("visibility ran");
    let s0 = &vis.fixed.samples().samples;
    assert_eq!(vis.fixed.more_samples.len(), 2);
    for more in &vis.fixed.more_samples {
        let s = &more.samples;
        assert!(std::sync::Arc::ptr_eq(&s.z, &s0.z), "depth plane shared");
        assert!(std::sync::Arc::ptr_eq(&s.prim, &s0.prim), "id plane shared");
        assert_ne!(s.i.as_ptr(), s0.i.as_ptr(), "own intensity plane");
    }
}

#[test]
fn every_dof_method_keeps_a_grey_scene_grey_in_three_channels() {
    for kind in [DofKind::Layered, DofKind::Luminance, DofKind::Downsample] {
        let mut h = HwConfig::default_config();
        h.dof.kind = kind;
        let grey = small_default();
        let mut colour = grey.clone();
        colour.image.colour = true;
        let g = render(&grey, &h);
        let c = render(&colour, &h);
        for (k, ch) in c.colour.as_ref().unwrap().channels.iter().enumerate() {
            assert!(ch.dac == g.dac, "{kind:?} channel {k}");
            assert!(ch.dac_ref == g.dac_ref, "{kind:?} channel {k} float");
        }
    }
}

#[test]
fn per_channel_widths_reach_their_channel() {
    let h = hw_text(
        "[accumulate]\nframe = [\"UQ5.0\", \"UQ6.0\", \"UQ5.0\"]\n[gamma]\ndac_bits = [5, 6, 5]\n",
    );
    assert!(h.per_channel());
    // Two values are neither one nor three: the message names the field and both forms.
    let bad = "[accumulate]\nframe = [\"UQ5.0\", \"UQ6.0\"]\n";
    let e = HwConfig::from_toml(&TomlFile::from_text("hw.toml", bad)).unwrap_err();
    assert_eq!((e.field.as_str(), e.line), ("accumulate.frame", Some(2)));
    assert!(
        e.msg.contains("UQ<int>.<frac>") && e.msg.contains("array of three"),
        "{e}"
    );
    assert_eq!(h.channel(1).accumulate.frame.format.to_string(), "UQ6.0");
    assert_eq!(
        h.channel(1).input.intensity.format.int_bits,
        6,
        "follows the frame"
    );
    assert_eq!(h.channel(2).gamma.dac_bits, 5);
    // A grey scene on per-channel hardware renders three channels.
    let s = small_default();
    let r = render(&s, &h);
    let c = r
        .colour
        .as_ref()
        .expect("per-channel widths render three channels");
    let rep = r.report.colour.as_ref().unwrap();
    let names: Vec<&str> = rep.channels.iter().map(|c| c.frame.as_str()).collect();
    assert_eq!(names, ["UQ5.0", "UQ6.0", "UQ5.0"]);
    assert_eq!(
        c.channels.iter().map(|k| k.bits).collect::<Vec<_>>(),
        [5, 6, 5]
    );
    for k in &c.channels {
        assert!(k.dac.iter().all(|&d| u32::from(d) < 1 << k.bits));
    }
    // Green has one more bit than red and blue everywhere, so its frame memory is larger.
    let frame = |c: usize| rep.channels[c].stages[0].cost.storage_bits;
    assert!(frame(1) > frame(0) && frame(0) == frame(2));
    // Each channel alone is the grey render with that channel's widths, its storage, LUT
    // bits and cycles that render's.
    for ch in 0..3 {
        let g = render(&s, &h.channel(ch));
        assert!(c.channels[ch].dac == g.dac, "channel {ch}");
        let lane = &rep.channels[ch];
        let geometry: u64 = ["input", "setup", "raster", "visibility"]
            .iter()
            .filter_map(|n| g.report.stages.iter().find(|st| st.name == *n))
            .map(|st| st.cost.storage_bits)
            .sum();
        assert_eq!(lane.storage_bits + geometry, g.report.storage_bits, "{ch}");
        assert_eq!(lane.cycles, g.report.cycles.total_cycles, "channel {ch}");
        assert_eq!(lane.bottleneck, g.report.cycles.bottleneck);
    }
    assert_eq!(rep.channels[0].cycles, r.report.cycles.total_cycles);
}

#[test]
fn a_flat_colour_field_is_flat_in_every_channel() {
    let quad = "[[object]]\nkind = \"quad\"\nspace = \"screen\"\n\
        vertices = [[-4, -4, 0.5], [68, -4, 0.5], [68, 52, 0.5], [-4, 52, 0.5]]\n\
        intensity = [[0.8, 0.3, 0.05], [0.8, 0.3, 0.05], [0.8, 0.3, 0.05], [0.8, 0.3, 0.05]]\n";
    let s = common::scene(64, 48, 0.0, quad);
    assert!(
        s.image.colour,
        "an [r, g, b] intensity makes a colour scene"
    );
    for filter in ["box", "tent"] {
        let h = hw_text(&format!("[accumulate]\nfilter = \"{filter}\"\n"));
        let r = render(&s, &h);
        let ch = &r.colour.as_ref().unwrap().channels;
        let first: Vec<u16> = ch.iter().map(|k| k.dac[0]).collect();
        for (k, c) in ch.iter().enumerate() {
            assert!(
                c.dac.iter().all(|&d| d == first[k]),
                "{filter}: channel {k} flat"
            );
            assert_eq!(
                c.dac, c.dac_ref,
                "{filter}: channel {k} equals its reference"
            );
        }
        assert!(first[0] > first[1] && first[1] > first[2], "{first:?}");
    }
}

#[test]
fn colour_scenes_parse_rgb_values_and_grey_ones() {
    let s = Scene::embedded("default-colour").expect("embedded");
    assert!(s.image.colour);
    assert_eq!(s.channels(), 3);
    assert_eq!(s.image.background, [0.03, 0.045, 0.08]);
    let grey = Scene::default_scene();
    assert!(!grey.image.colour && grey.channels() == 1);
    assert_eq!(grey.image.background, [0.05; 3]);
    // An array of the wrong length names the field and the forms it takes.
    let bad =
        common::scene_toml(8, 8, 0.0, "").replace("background = 0", "background = [0.1, 0.2]");
    let e = Scene::from_toml(&TomlFile::from_text("c.toml", &bad)).unwrap_err();
    assert_eq!(e.field, "image.background");
    assert!(
        e.msg.contains("[r, g, b]") && e.msg.contains("got 2 values"),
        "{e}"
    );
    // `colour = false` renders a scene with colours as one channel (channel R's values).
    let forced = common::scene_toml(8, 8, 0.0, "").replace(
        "background = 0",
        "background = [0.1, 0.2, 0.3]\ncolour = false",
    );
    let s = Scene::from_toml(&TomlFile::from_text("c.toml", &forced)).unwrap();
    assert_eq!(s.channels(), 1);
}

#[test]
fn the_binary_writes_an_rgb_png_and_reports_each_channel() {
    let dir = std::env::temp_dir().join(format!("igemu-colour-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let out = dir.join("c.png");
    let o = out.to_str().unwrap();
    let (code, stdout, stderr) = common::igemu(&["render", "default-colour", "-o", o]);
    assert_eq!(code, 0, "{stderr}");
    assert!(stdout.contains("per channel"), "{stdout}");
    for name in [
        "R (UQ12.0, 8 bits)",
        "G (UQ12.0, 8 bits)",
        "B (UQ12.0, 8 bits)",
    ] {
        assert!(stdout.contains(name), "{name}: {stdout}");
    }
    let img = image::open(&out).unwrap();
    assert_eq!(img.color(), image::ColorType::Rgb8);
    let rgb = img.to_rgb8();
    // The cone is red: somewhere red far exceeds blue.
    assert!(
        rgb.pixels()
            .any(|p| u32::from(p[0]) > 2 * u32::from(p[2]) + 40)
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

/// The width paper's colour-mix distortion: a saturated shaded ramp (R:G:B = 5:2:1) through
/// 5-6-5 frame words shifts the hue of smooth surfaces and leaves pixels beyond the 2.3 JND;
/// 8-8-8 shifts it less and leaves none; 12-bit words hardly at all.
#[test]
fn a_saturated_ramp_at_565_shifts_hue_that_wider_words_do_not() {
    let quad = "[[object]]\nkind = \"quad\"\nspace = \"screen\"\n\
        vertices = [[-4, -4, 0.5], [260, -4, 0.5], [260, 36, 0.5], [-4, 36, 0.5]]\n\
        intensity = [[0.1, 0.04, 0.02], [0.9, 0.36, 0.18], [0.9, 0.36, 0.18], [0.1, 0.04, 0.02]]\n";
    let s = common::scene(256, 32, 0.0, quad);
    let run = |frame: &str| {
        let h = hw_text(&format!("[accumulate]\nframe = {frame}\n"));
        let r = render(&s, &h);
        let c = r.report.colour.expect("colour");
        (c.hue_shift, c.delta_e)
    };
    let (h565, e565) = run("[\"UQ5.0\", \"UQ6.0\", \"UQ5.0\"]");
    let (h888, e888) = run("[\"UQ8.0\", \"UQ8.0\", \"UQ8.0\"]");
    let (h12, e12) = run("\"UQ12.0\"");
    // Every smooth pixel of the ramp is chromatic, and most of the ramp is smooth (the
    // reference spans at most 2 codes per channel over 5x5 pixels).
    assert_eq!(h565.pixels, h565.smooth_pixels);
    assert!(h565.pixels > 256 * 32 / 2, "{h565:?}");
    assert!(h565.mean_deg > 3.0 * h888.mean_deg, "{h565:?} {h888:?}");
    assert!(h888.mean_deg > 3.0 * h12.mean_deg, "{h888:?} {h12:?}");
    assert!(
        h565.mean_deg > 1.0 && h12.mean_deg < 0.1,
        "{h565:?} {h12:?}"
    );
    assert!(e565.over_jnd > 0 && e888.over_jnd == 0, "{e565:?} {e888:?}");
    assert!(e565.mean > e888.mean && e888.mean > e12.mean);
}

#[test]
fn a_log_coded_colour_sample_buffer_stores_depth_and_id_once() {
    let mut h = HwConfig::preset("log8-logadd").expect("preset");
    h.dof.kind = DofKind::Luminance;
    let mut s = small_default();
    s.image.colour = true;
    let r = render(&s, &h);
    let lanes = &r.colour.as_ref().unwrap().lanes;
    let buffer = |steps: &[pipeline::Step]| {
        let st = steps
            .iter()
            .find(|st| st.id.name() == "logdomain")
            .expect("log coding");
        let m = st
            .outcome
            .report
            .cost
            .memories
            .iter()
            .find(|m| m.name == igemu::stage::visibility::SAMPLE_BUFFER)
            .expect("the sample buffer")
            .clone();
        for p in &st.outcome.packs {
            assert!(p.verified && p.problem.is_none(), "{p:?}");
        }
        m
    };
    let (r0, g, b) = (buffer(&r.steps), buffer(&lanes[0]), buffer(&lanes[1]));
    let code = h.coding.log_bits;
    assert_eq!((g.width, b.width), (code, code), "G and B store their code");
    assert!(r0.width > code, "R's word holds depth and id with its code");
    assert_eq!((r0.depth, g.depth), (b.depth, b.depth));
    // The grey render's log-coded sample word is R's.
    let grey = render(&small_default(), &h);
    assert_eq!(buffer(&grey.steps).width, r0.width);
}

/// Each channel's frame-memory total of a colour render (frame LSBs).
fn channel_totals(r: &Render) -> [u64; 3] {
    let lanes = &r.colour.as_ref().expect("colour").lanes;
    std::array::from_fn(|c| {
        let steps = if c == 0 { &r.steps } else { &lanes[c - 1] };
        let st = steps.iter().find(|s| s.id.name() == "accumulate").unwrap();
        st.outcome
            .taps
            .fixed
            .frame()
            .frame
            .acc
            .iter()
            .map(|&a| u64::from(a))
            .sum()
    })
}

proptest::proptest! {
    #![proptest_config(proptest::prelude::ProptestConfig::with_cases(24))]

    /// Equal energy per channel: with a frame word wide enough to hold every product
    /// exactly, a coloured one-pixel light point and a coloured quad of one pixel
    /// accumulate the same total in each channel at every sub-pixel position (box and tent).
    #[test]
    fn equal_energy_holds_in_every_channel(x in 4.0f64..11.0, y in 4.0f64..11.0) {
        let rgb = [0.7, 0.3, 0.1];
        let point = |x: f64, y: f64| format!(
            "[[object]]\nkind = \"light_point\"\nspace = \"screen\"\nposition = [{x}, {y}, 0.5]\nintensity = [0.7, 0.3, 0.1]\nsize = 1.0\n\n"
        );
        let quad = |x: f64, y: f64| {
            let v = |a: f64, b: f64| format!("[{a}, {b}, 0.5]");
            let (a, b, c, d) = (v(x, y), v(x + 1.0, y), v(x + 1.0, y + 1.0), v(x, y + 1.0));
            let i = format!("[[{0}, {1}, {2}], [{0}, {1}, {2}], [{0}, {1}, {2}]]", rgb[0], rgb[1], rgb[2]);
            format!(
                "[[object]]\nkind = \"triangle\"\nspace = \"screen\"\nvertices = [{a}, {b}, {c}]\nintensity = {i}\n\n\
                 [[object]]\nkind = \"triangle\"\nspace = \"screen\"\nvertices = [{a}, {c}, {d}]\nintensity = {i}\n\n"
            )
        };
        for filter in ["box", "tent"] {
            let h = hw_text(&format!("preset = \"linear12\"\n[accumulate]\nfilter = \"{filter}\"\nframe = \"UQ12.14\"\n"));
            let totals = |objects: String| channel_totals(&render(&common::scene(16, 16, 0.0, &objects), &h));
            let reference = totals(point(8.0, 8.0));
            proptest::prop_assert!(reference[0] > reference[1] && reference[1] > reference[2]);
            proptest::prop_assert_eq!(totals(point(x, y)), reference);
            proptest::prop_assert_eq!(totals(quad(x, y)), reference);
        }
    }
}

/// The decoded pixels of an HTML picture's `data:image/png;base64,...` URI.
fn decode_picture(uri: &str) -> image::DynamicImage {
    use base64::Engine;
    let b64 = uri.strip_prefix("data:image/png;base64,").expect("a PNG");
    let png = base64::engine::general_purpose::STANDARD
        .decode(b64)
        .expect("base64");
    image::load_from_memory(&png).expect("a PNG decodes")
}

/// The HTML report of a colour render shows it in colour (RGB images, each channel's
/// difference, the CIEDE2000 heat map with its legend, the colour figures and one line per
/// channel); a grey render's page has no colour section. Runs without a browser
/// (tests/browser.rs opens the page in Chromium).
#[test]
fn the_html_report_of_a_colour_render_shows_colour_and_a_grey_one_does_not() {
    let mut s = Scene::embedded("default-colour").expect("embedded");
    (s.image.width, s.image.height) = (160, 120);
    let h = hw_text("[accumulate]\nframe = [\"UQ5.0\", \"UQ6.0\", \"UQ5.0\"]\n");
    let r = render(&s, &h);
    let html = igemu::html::render_page(&s, &h, &r, "c.html").unwrap_or_else(|e| panic!("{e}"));
    for needle in [
        "<h2 id=\"colour\">Colour</h2>",
        "alt=\"fixed pipeline\"",
        "alt=\"float reference\"",
        "alt=\"difference, channel R\"",
        "alt=\"difference, channel G\"",
        "alt=\"difference, channel B\"",
        "alt=\"CIEDE2000 heat map\"",
        "R, G and B DAC codes (8-8-8 bits)",
        "#0000ff\"></i>1<",
        "2.3: the JND",
        "5 and above",
        "CIEDE2000 p99",
        "hue shift mean",
        "contour steps over R, G, B",
        "identical DAC codes, channel R",
    ] {
        assert!(html.contains(needle), "the colour page lacks {needle:?}");
    }
    let table = &html[html.find("id=\"colour-channels\"").expect("channel table")..];
    let table = &table[..table.find("</table>").unwrap()];
    for (name, frame) in [("R", "UQ5.0"), ("G", "UQ6.0"), ("B", "UQ5.0")] {
        let row = format!("<td class=\"t\">{name}</td><td class=\"t\">{frame}</td>");
        assert!(table.contains(&row), "{row}: {table}");
    }
    // The pictures are RGB: the fixed image is not grey, the heat map is the one
    // `--delta-e-out` writes.
    let page = igemu::html::render::page(&s, &h, &r).unwrap();
    let fixed = decode_picture(&page.pictures[0].uri);
    assert_eq!(page.pictures[0].title, "fixed pipeline");
    assert_eq!(fixed.color(), image::ColorType::Rgb8);
    assert!(fixed.to_rgb8().pixels().any(|p| p[0] != p[1]), "grey");
    let colour = page.colour.as_ref().expect("a colour section");
    let heat = decode_picture(&colour.delta_e.uri).to_rgb8().into_raw();
    let c = r.colour.as_ref().unwrap();
    assert_eq!(heat, igemu::colour::delta_e_image(&c.delta_e, 160, 120));
    assert_eq!(colour.channels.len(), 3);

    let grey = small_default();
    let hg = HwConfig::default_config();
    let g = render(&grey, &hg);
    let html = igemu::html::render_page(&grey, &hg, &g, "g.html").unwrap();
    for needle in ["id=\"colour", "CIEDE2000", "channel R", "channel G"] {
        assert!(!html.contains(needle), "the grey page has {needle:?}");
    }
    let page = igemu::html::render::page(&grey, &hg, &g).unwrap();
    assert!(page.colour.is_none());
    let fixed = decode_picture(&page.pictures[0].uri);
    assert_eq!(fixed.color(), image::ColorType::L8);
    // The cycle timelines of both depth-of-field schedules, the chosen one first.
    let timelines: Vec<&str> = page
        .plots
        .iter()
        .map(|p| p.title.as_str())
        .filter(|t| t.starts_with("cycle simulation"))
        .collect();
    assert_eq!(timelines.len(), 2, "{timelines:?}");
    assert!(
        timelines[0].contains("dof.schedule = \"stream\""),
        "{timelines:?}"
    );
    assert!(
        timelines[1].contains("dof.schedule = \"frame\""),
        "{timelines:?}"
    );
    for s in ["stream", "frame"] {
        let t = format!("dof.schedule = &quot;{s}&quot;");
        assert!(html.contains(&t), "the page lacks {t:?}");
    }
    // Every timed stage has a row, logdomain and dither included: a log-coded frame with
    // error diffusion (a log-potentiate frame; log-add with a dither is tests/logadd_dither.rs).
    let mut hl = HwConfig::preset("log8-potentiate").unwrap();
    hl.dither.kind = igemu::config::DitherKind::FloydSteinberg;
    let l = render(&grey, &hl);
    let page = igemu::html::render::page(&grey, &hl, &l).unwrap();
    let rows: Vec<&str> = page
        .plots
        .iter()
        .filter(|p| p.title.starts_with("cycle simulation"))
        .map(|p| p.caption.as_str())
        .collect();
    assert_eq!(rows.len(), 2, "{rows:?}");
    for caption in rows {
        for stage in ["logdomain", "accumulate", "dof", "gamma", "dither"] {
            assert!(caption.contains(stage), "{stage}: {caption}");
        }
    }
}

/// A folder for the binary's files and the saturated ramp (R:G:B = 5:2:1) as a scene file in
/// it: G differs from R everywhere.
fn ramp_file(name: &str) -> (std::path::PathBuf, String) {
    let dir = std::env::temp_dir().join(format!("igemu-colour-{name}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let quad = "[[object]]\nkind = \"quad\"\nspace = \"screen\"\n\
        vertices = [[-4, -4, 0.5], [260, -4, 0.5], [260, 36, 0.5], [-4, 36, 0.5]]\n\
        intensity = [[0.1, 0.04, 0.02], [0.9, 0.36, 0.18], [0.9, 0.36, 0.18], [0.1, 0.04, 0.02]]\n";
    let path = dir.join("ramp.toml");
    std::fs::write(&path, common::scene_toml(256, 32, 0.0, quad)).unwrap();
    let p = path.to_string_lossy().into_owned();
    (dir, p)
}

#[test]
fn ranges_lists_every_channel_and_exports_a_typedef_per_channel() {
    let (dir, ramp) = ramp_file("ranges");
    let hw = dir.join("hw.toml");
    std::fs::write(
        &hw,
        "[accumulate]\nframe = [\"UQ5.0\", \"UQ6.0\", \"UQ5.0\"]\n",
    )
    .unwrap();
    let hw = hw.to_str().unwrap();
    let (code, stdout, stderr) = common::igemu(&["ranges", &ramp, "--json"]);
    assert_eq!(code, 0, "{stderr}");
    let rows: Vec<serde_json::Value> = serde_json::from_str(&stdout).unwrap();
    let of = |signal: &str| -> Vec<(String, i64)> {
        rows.iter()
            .filter(|r| r["signal"] == signal)
            .map(|r| {
                (
                    r["channel"].as_str().unwrap_or("-").to_string(),
                    r["max"].as_i64().unwrap(),
                )
            })
            .collect()
    };
    // Each stage after visibility once per channel; the vertex intensity per channel.
    let frame = of("accumulate.frame");
    let names: Vec<&str> = frame.iter().map(|(c, _)| c.as_str()).collect();
    assert_eq!(names, ["R", "G", "B"], "{stdout}");
    assert!(
        frame[0].1 > frame[1].1 && frame[1].1 > frame[2].1,
        "R:G:B = 5:2:1: {frame:?}"
    );
    for (c, signal) in ["R", "G", "B"].iter().zip([
        "input.intensity.r",
        "input.intensity.g",
        "input.intensity.b",
    ]) {
        assert_eq!(of(signal).len(), 1, "{signal}");
        assert_eq!(of(signal)[0].0, *c);
    }
    // Shared signals are listed once, without a channel.
    let z = rows
        .iter()
        .filter(|r| r["signal"] == "input.z")
        .collect::<Vec<_>>();
    assert_eq!(z.len(), 1);
    assert!(z[0].get("channel").is_none());
    // The text table has a channel column.
    let (code, text, _) = common::igemu(&["ranges", &ramp, "--hw", hw]);
    assert_eq!(code, 0);
    assert!(text.lines().next().unwrap().contains("channel"), "{text}");
    let g_frame = text
        .lines()
        .find(|l| l.contains("accumulate.frame") && l.split_whitespace().nth(1) == Some("G"))
        .expect("channel G's frame");
    assert!(g_frame.contains("UQ6.0"), "{g_frame}");
    // The typedefs: one per channel of each per-channel word, with its width.
    let (code, ap, _) = common::igemu(&["ranges", &ramp, "--hw", hw, "--export", "ap_fixed"]);
    assert_eq!(code, 0);
    for line in [
        "typedef ap_ufixed<5, 5, AP_RND_CONV, AP_SAT> accumulate_frame_r_t;",
        "typedef ap_ufixed<6, 6, AP_RND_CONV, AP_SAT> accumulate_frame_g_t;",
        "typedef ap_ufixed<5, 5, AP_RND_CONV, AP_SAT> accumulate_frame_b_t;",
        "typedef ap_ufixed<10, 6, AP_RND_CONV, AP_SAT> input_intensity_g_t;",
        "typedef ap_ufixed<8, 8, AP_RND_CONV, AP_SAT> gamma_dac_b_t;",
        "typedef ap_ufixed<24, 0, AP_TRN, AP_SAT> visibility_z_t;",
    ] {
        assert!(ap.contains(line), "{line}: {ap}");
    }
    assert!(!ap.contains("accumulate_frame_t"), "{ap}");
    let (_, v, _) = common::igemu(&["ranges", &ramp, "--export", "verilog"]);
    assert!(
        v.contains("localparam integer ACCUMULATE_FRAME_G_W = 12;"),
        "{v}"
    );
    // A grey render: no channel, one typedef each, as before.
    let (code, grey, _) = common::igemu(&["ranges", "--json"]);
    assert_eq!(code, 0);
    assert!(!grey.contains("\"channel\"") && grey.contains("\"input.intensity\""));
    let (_, grey_ap, _) = common::igemu(&["ranges", "--export", "ap_fixed"]);
    assert!(
        grey_ap.contains(" accumulate_frame_t;") && !grey_ap.contains("_r_t"),
        "{grey_ap}"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn hdl_vectors_take_the_lane_of_the_channel_asked_for() {
    let (dir, ramp) = ramp_file("hdl");
    let vectors = |stage: &str, channel: Option<&str>| -> (String, Vec<u8>) {
        let out = dir.join(format!("{stage}-{}", channel.unwrap_or("default")));
        let o = out.to_str().unwrap();
        let mut args = vec!["hdl", "vectors", "--stage", stage, &ramp, "--out", o];
        if let Some(c) = channel {
            args.extend(["--channel", c]);
        }
        let (code, stdout, stderr) = common::igemu(&args);
        assert_eq!(code, 0, "{stderr}");
        (stdout, std::fs::read(out.join("vectors.hex")).unwrap())
    };
    // Equal widths (linear12) in every channel: the gamma LUT's scene taps are the
    // channel's frame codes, so G's vectors differ from R's; R is the default.
    let (r_text, r) = vectors("gamma", Some("r"));
    let (g_text, g) = vectors("gamma", Some("g"));
    let (_, default) = vectors("gamma", None);
    assert!(
        r_text.contains("| channel R |") && g_text.contains("| channel G |"),
        "{g_text}"
    );
    assert_eq!(r, default, "R is the default channel");
    assert_ne!(r, g, "G's frame codes are not R's");
    // The MAC's scene taps are the channel's vertex intensities.
    let (_, ar) = vectors("accumulate", None);
    let (_, ab) = vectors("accumulate", Some("b"));
    assert_ne!(ar, ab);
    // A grey render has no channel to choose.
    let out = dir.join("grey");
    let o = out.to_str().unwrap();
    let (code, _, stderr) = common::igemu(&[
        "hdl",
        "vectors",
        "--stage",
        "gamma",
        "--out",
        o,
        "--channel",
        "g",
    ]);
    assert_eq!(code, 2, "{stderr}");
    assert!(
        stderr.contains("--channel") && stderr.contains("colour"),
        "{stderr}"
    );
    assert!(!out.exists(), "nothing written");
    std::fs::remove_dir_all(&dir).unwrap();
}

/// The accumulate stage picks the word of its window sums from each channel's intensity
/// format instead of scanning the sample buffer: every sample code of every channel lies
/// within that format, on per-channel widths and on the colour scene.
#[test]
fn sample_codes_stay_within_their_channel_format() {
    let narrow = hw_text("[accumulate]\nframe = [\"UQ5.0\", \"UQ6.0\", \"UQ5.0\"]\n");
    for (scene, hw) in [
        (small_default(), narrow),
        (
            Scene::embedded("default-colour").unwrap(),
            HwConfig::default_config(),
        ),
    ] {
        let (_, taps) = pipeline::run_through(
            &scene,
            &hw,
            RunOptions::FIXED_ONLY,
            igemu::stage::StageId::Visibility,
        )
        .unwrap();
        for c in 0..3 {
            let lane = taps.lane(c);
            let codes = &lane.fixed.samples().samples.i;
            let max = hw.channel(c).input.intensity.format.max_code();
            let top = codes.iter().copied().max().unwrap();
            assert!(
                i64::from(top) <= max,
                "{} channel {c}: {top} > {max}",
                scene.name
            );
            assert!(top > 0, "{} channel {c}: a lit sample", scene.name);
        }
    }
}
