//! Colour sequences: every frame's R, G, B through the fixed pipeline and its reference,
//! the temporal metrics on the displayed luminance `Y` of the three channels, CIEDE2000 per
//! frame, and an RGB animated PNG; bit-identical to single colour renders, with and without
//! reuse, and with the float reference off.

mod common;

use igemu::config::HwConfig;
use igemu::files::TomlFile;
use igemu::pipeline::render;
use igemu::scene::Scene;
use igemu::stage::RunOptions;

/// A 96x64 colour sequence: a saturated quad and a reddish light point moving 0.37 px per
/// frame over it, six frames.
fn colour_text() -> String {
    let objects = "[[object]]\nkind = \"quad\"\nspace = \"screen\"\n\
        vertices = [[-4, 40, 0.6], [100, 40, 0.6], [100, 68, 0.6], [-4, 68, 0.6]]\n\
        intensity = [[0.1, 0.3, 0.6], [0.7, 0.3, 0.1], [0.7, 0.3, 0.1], [0.1, 0.3, 0.6]]\n\n\
        [[object]]\nkind = \"light_point\"\nspace = \"screen\"\nposition = [30.2, 20.6, 0.4]\n\
        intensity = [0.9, 0.5, 0.3]\nsize = 1.0\n\n\
        [sequence]\nframes = 6\n\n\
        [[sequence.object]]\nobject = 1\nframe = 0\ntranslate = [0.0, 0.0, 0.0]\n\n\
        [[sequence.object]]\nobject = 1\nframe = 5\ntranslate = [1.85, 0.55, 0.0]\n";
    common::scene_toml(96, 64, 0.05, objects)
}

fn colour_sequence() -> Scene {
    let text = colour_text();
    Scene::from_toml(&TomlFile::from_text("colour-seq.toml", &text))
        .unwrap_or_else(|e| panic!("{e}\n{text}"))
}

use common::run_sequence as run;

#[test]
fn a_colour_sequence_equals_single_colour_renders_with_and_without_reuse() {
    let scene = colour_sequence();
    assert!(scene.image.colour);
    let hw = HwConfig::default_config();
    let (r, frames) = run(&scene, &hw, 0..6, true, true);
    assert_eq!(r.frames.len(), 6);
    for (k, (fixed, reference)) in frames.iter().enumerate() {
        let single = render(&scene.frame(k as u32).unwrap(), &hw, RunOptions::FAST).unwrap();
        let c = single.colour.as_ref().expect("a colour render");
        assert_eq!(fixed.len(), 3);
        for (ch, codes) in c.channels.iter().enumerate() {
            assert_eq!(fixed[ch], codes.dac, "frame {k} channel {ch}");
            assert_eq!(
                reference.as_ref().unwrap()[ch],
                codes.dac_ref,
                "frame {k} ch {ch}"
            );
        }
        let rec = &r.frames[k];
        let de = &single.report.colour.as_ref().unwrap().delta_e;
        assert_eq!(rec.delta_e_mean, Some(de.mean), "frame {k}");
        assert_eq!(rec.delta_e_max, Some(de.max), "frame {k}");
        assert!(rec.identical_fraction.unwrap() > 0.0);
    }
    // The moving light point is a small object, followed on the luminance of R, G and B.
    assert_eq!(r.temporal.objects.len(), 1, "{:?}", r.temporal.objects);
    let o = &r.temporal.objects[0];
    assert_eq!(o.total_fixed.len(), 6);
    assert!(
        o.total_fixed.iter().all(|&t| t > 0.0),
        "{:?}",
        o.total_fixed
    );
    assert_eq!(r.temporal.pairs, 5);
    // Without reuse, and on the fixed-only path, the same codes.
    let (nr, no_reuse) = run(&scene, &hw, 0..6, true, false);
    assert_eq!(nr.reuse.stages_reused, 0);
    let (_, fixed_only) = run(&scene, &hw, 0..6, false, true);
    for k in 0..6 {
        assert_eq!(frames[k], no_reuse[k], "frame {k}");
        assert_eq!(frames[k].0, fixed_only[k].0, "frame {k}");
        assert!(fixed_only[k].1.is_none());
    }
    assert_eq!(nr.temporal.objects[0].total_fixed, o.total_fixed);
}

/// A colour scene whose channels are all equal (grey intensities, `colour = true`) has the
/// grey sequence's codes in every channel, and its luminance `Y` is the grey luminance: the
/// small objects' totals agree to 1e-4 relative (the display white is scaled to the D65
/// white, which differs from sRGB's white by ~1e-5).
#[test]
fn a_grey_scene_run_as_colour_has_the_grey_temporal_figures() {
    let text = include_str!("../src/scene/flypast.toml");
    let grey = Scene::from_toml(&TomlFile::from_text("flypast.toml", text)).unwrap();
    let colour_text = text.replacen("[image]\n", "[image]\ncolour = true\n", 1);
    let colour = Scene::from_toml(&TomlFile::from_text("flypast-c.toml", &colour_text)).unwrap();
    assert!(colour.image.colour && !grey.image.colour);
    let hw = HwConfig::default_config();
    let (g, gf) = run(&grey, &hw, 0..3, true, true);
    let (c, cf) = run(&colour, &hw, 0..3, true, true);
    for k in 0..3 {
        for ch in 0..3 {
            assert_eq!(cf[k].0[ch], gf[k].0[0], "frame {k} channel {ch}");
        }
    }
    assert_eq!(g.temporal.objects.len(), c.temporal.objects.len());
    assert!(!g.temporal.objects.is_empty());
    for (a, b) in g.temporal.objects.iter().zip(&c.temporal.objects) {
        for (x, y) in a.total_fixed.iter().zip(&b.total_fixed) {
            assert!((x - y).abs() <= 1e-4 * x.abs().max(1.0), "{x} vs {y}");
        }
    }
    let (gm, cm) = (
        g.temporal.max_excess_weber.unwrap(),
        c.temporal.max_excess_weber.unwrap(),
    );
    assert!((gm - cm).abs() <= 1e-3 * gm.max(1.0), "{gm} vs {cm}");
    assert!(g.frames.iter().all(|f| f.delta_e_max.is_none()));
    assert!(c.frames.iter().all(|f| f.delta_e_max.is_some()));
}

/// `igemu sequence FILE --apng --json -o` on a colour sequence: exit 0, an RGB APNG of six
/// frames (fixed beside the difference), RGB PNGs per frame, CIEDE2000 per frame in the JSON.
#[test]
fn the_command_writes_an_rgb_animated_png_of_a_colour_sequence() {
    let dir = std::env::temp_dir().join(format!("igemu-seq-colour-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = |n: &str| dir.join(n).to_string_lossy().into_owned();
    std::fs::write(path("colour-seq.toml"), colour_text()).unwrap();
    let (code, out, err) = common::igemu(&[
        "sequence",
        &path("colour-seq.toml"),
        "--apng",
        &path("seq.png"),
        "-o",
        &path("frame.png"),
        "--json",
    ]);
    assert_eq!(code, 0, "{err}");
    let j: serde_json::Value = serde_json::from_str(&out).expect("JSON report");
    let frames = j["frames"].as_array().unwrap();
    assert_eq!(frames.len(), 6);
    assert!(frames.iter().all(|f| f["delta_e_max"].is_number()), "{out}");
    let bytes = std::fs::read(path("seq.png")).unwrap();
    let dec = png::Decoder::new(std::io::Cursor::new(bytes));
    let mut reader = dec.read_info().unwrap();
    let info = reader.info();
    assert_eq!(info.color_type, png::ColorType::Rgb);
    assert_eq!((info.width, info.height), (2 * 96, 64));
    assert_eq!(info.animation_control.map(|a| a.num_frames), Some(6));
    let mut buf = vec![0; reader.output_buffer_size().unwrap()];
    let mut decoded = 0;
    while reader.next_frame(&mut buf).is_ok() {
        decoded += 1;
        if decoded == 6 {
            break;
        }
    }
    assert_eq!(decoded, 6);
    // Each frame as an RGB PNG.
    let first = image::open(dir.join("frame-0000.png")).expect("frame 0 written");
    assert_eq!(first.color(), image::ColorType::Rgb8);
    std::fs::remove_dir_all(&dir).ok();
}
