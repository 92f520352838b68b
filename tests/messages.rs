//! Every message names the field: a corpus of malformed scene and hardware files (wrong types
//! of every kind of field, duplicate keys and tables, wrong table kinds, unknown keys,
//! truncated files, strings where numbers belong, arrays of the wrong length, out-of-range
//! numbers, nested errors inside `[[object]]`). Each one is refused by the library with the
//! file, the line, the dotted field path and a hint of the expected type or range, and by the
//! binary with exit 2 and the same message (no panic).

mod common;

use igemu::config::HwConfig;
use igemu::error::FileError;
use igemu::files::TomlFile;
use igemu::scene::Scene;

/// A scene with every section and every kind of object (indices: 0 sphere, 1 torus, 2 cone,
/// 3 screen-space triangle, 4 quad, 5 line, 6 light point, 7 cylinder).
const SCENE: &str = r#"name = "m"
[image]
width = 64
height = 48
background = 0.05

[camera]
position = [0.0, 0.0, 0.0]
look_at = [0.0, 0.0, -1.0]
up = [0.0, 1.0, 0.0]
fov_y_deg = 40.0
near = 2.0
far = 50.0

[camera.lens]
kind = "thin_lens"
focal_length = 0.02
lens_radius = 0.06
focus_distance = 10.0
deep = 1.8
coc = 0.000035

[display]
contrast = 100.0
gamma = 2.4
weber = 0.02
b_max = 100.0
refresh_hz = 60.0

[shading]
ambient = 0.08

[[light]]
direction = [-0.45, 0.65, 0.6]
intensity = 0.85

[[object]]
kind = "sphere"
center = [0.3, 0.0, -10.0]
radius = 1.8
tessellation = 16
reflectance = 0.75
specular = 0.3
shininess = 30.0

[[object]]
kind = "torus"
center = [3.6, 2.0, -18.0]
axis = [0.0, 1.0, 0.8]
major_radius = 2.5
minor_radius = 0.8
tessellation = 12

[[object]]
kind = "cone"
base = [-1.0, -1.3, -5.0]
axis = [0.0, 1.8, 0.0]
radius = 0.6
capped = true

[[object]]
kind = "triangle"
space = "screen"
vertices = [[1.0, 1.0, 0.5], [30.0, 2.0, 0.5], [2.0, 30.0, 0.5]]
intensity = [0.2, 0.4, 0.6]

[[object]]
kind = "quad"
vertices = [[-1.0, -1.0, -6.0], [1.0, -1.0, -6.0], [1.0, 1.0, -6.0], [-1.0, 1.0, -6.0]]
emissive = 0.1

[[object]]
kind = "line"
from = [-1.0, 1.0, -8.0]
to = [1.0, 1.5, -8.0]
intensity = 1.0
width = 1.5

[[object]]
kind = "light_point"
position = [0.5, -0.5, -6.0]
intensity = 2.0
size = 1.0

[[object]]
kind = "cylinder"
base = [2.0, -1.0, -7.0]
axis = [0.0, 1.0, 0.0]
radius = 0.4
"#;

/// A hardware file with every section.
const HW: &str = r#"preset = "linear12"
[input]
coord = "Q13.4"
z = "UQ0.24"
quant = "RND_CONV"

[raster]
samples = 4
guard_band = 64
interp_guard_bits = 14

[visibility]
z = "UQ0.24"

[accumulate]
filter = "tent"
weight_bits = 10
gaussian_sigma = 0.5
frame = "UQ12.0"

[gamma]
dac_bits = 8
correction = true

[cycles]
clock_mhz = 100.0
tile = 16

[cycles.raster]
lanes = 4

[dither]
kind = "none"
frac_bits = 4

[dof]
kind = "layered"
sigma = "paper"
sigma_rom_bits = 10
p = 0.1
max_half_size = 32

[coding]
kind = "linear"
log_bits = 8
interpolate = false
"#;

/// One malformed file: `drop` (a unique piece of the base text, or "") is removed, then
/// `from` (a unique piece) becomes `to`; `cut` > 0
/// truncates the result after the first occurrence of `to` plus `cut - 1` characters
/// (1: right after `to`). The error must name `field`, be on the line of `at` (the first
/// line of `to` when empty) and contain `hint`.
struct Case {
    drop: &'static str,
    from: &'static str,
    to: &'static str,
    cut: usize,
    field: &'static str,
    at: &'static str,
    hint: &'static str,
}

const fn c(
    from: &'static str,
    to: &'static str,
    field: &'static str,
    at: &'static str,
    hint: &'static str,
) -> Case {
    Case {
        drop: "",
        from,
        to,
        cut: 0,
        field,
        at,
        hint,
    }
}

const fn cut(
    from: &'static str,
    to: &'static str,
    field: &'static str,
    at: &'static str,
    hint: &'static str,
) -> Case {
    Case {
        drop: "",
        from,
        to,
        cut: 1,
        field,
        at,
        hint,
    }
}

/// A case that first removes `drop` from the base.
const fn d(
    drop: &'static str,
    from: &'static str,
    to: &'static str,
    field: &'static str,
    at: &'static str,
    hint: &'static str,
) -> Case {
    Case {
        drop,
        from,
        to,
        cut: 0,
        field,
        at,
        hint,
    }
}

/// The scene's `[[light]]` block.
const LIGHT: &str = "[[light]]\ndirection = [-0.45, 0.65, 0.6]\nintensity = 0.85\n";

const LEN: &str = "in [1e-9, 1e9]";
const V3: &str = "exactly 3 finite numbers";

const SCENE_CASES: &[Case] = &[
    // Wrong types, strings where numbers belong.
    c(
        "width = 64",
        "width = \"64\"",
        "image.width",
        "",
        "an integer in 1..=8192",
    ),
    c(
        "height = 48",
        "height = 48.5",
        "image.height",
        "",
        "an integer in 1..=8192",
    ),
    c(
        "background = 0.05",
        "background = \"dark\"",
        "image.background",
        "",
        "in [0, 1]",
    ),
    c("near = 2.0", "near = true", "camera.near", "", LEN),
    c("far = 50.0", "far = [50.0]", "camera.far", "", LEN),
    c(
        "fov_y_deg = 40.0",
        "fov_y_deg = \"40\"",
        "camera.fov_y_deg",
        "",
        "in [0.001, 180)",
    ),
    c(
        "kind = \"thin_lens\"",
        "kind = 3",
        "camera.lens.kind",
        "",
        "\"pinhole\" or \"thin_lens\"",
    ),
    c(
        "focal_length = 0.02",
        "focal_length = \"0.02\"",
        "camera.lens.focal_length",
        "",
        LEN,
    ),
    c(
        "lens_radius = 0.06",
        "lens_radius = { r = 1 }",
        "camera.lens.lens_radius",
        "",
        LEN,
    ),
    c(
        "contrast = 100.0",
        "contrast = \"high\"",
        "display.contrast",
        "",
        "in [2, 1e9]",
    ),
    c(
        "gamma = 2.4",
        "gamma = true",
        "display.gamma",
        "",
        "in (1, 5]",
    ),
    c(
        "ambient = 0.08",
        "ambient = [0.1]",
        "shading.ambient",
        "",
        "in [0, 1]",
    ),
    c(
        "intensity = 0.85",
        "intensity = \"bright\"",
        "light[0].intensity",
        "",
        "in [0, 1e6]",
    ),
    c(
        "tessellation = 16",
        "tessellation = \"x\"",
        "object[0].tessellation",
        "",
        "3..=1024",
    ),
    c(
        "tessellation = 12",
        "tessellation = 16.5",
        "object[1].tessellation",
        "",
        "3..=1024",
    ),
    c(
        "radius = 1.8",
        "radius = \"1.8\"",
        "object[0].radius",
        "",
        "without quotes",
    ),
    c(
        "capped = true",
        "capped = \"yes\"",
        "object[2].capped",
        "",
        "true or false",
    ),
    c(
        "emissive = 0.1",
        "emissive = \"glow\"",
        "object[4].emissive",
        "",
        "in [0, 1e6]",
    ),
    c(
        "width = 1.5",
        "width = \"wide\"",
        "object[5].width",
        "",
        "pixels",
    ),
    c("size = 1.0", "size = true", "object[6].size", "", "pixels"),
    c(
        "kind = \"sphere\"",
        "kind = 5",
        "object[0].kind",
        "",
        "\"light_point\"",
    ),
    c(
        "space = \"screen\"",
        "space = 1",
        "object[3].space",
        "",
        "\"world\" or \"screen\"",
    ),
    c(
        "radius = 0.4",
        "radius = 1979-05-27",
        "object[7].radius",
        "",
        LEN,
    ),
    // Arrays of the wrong length or with wrong elements.
    c(
        "position = [0.0, 0.0, 0.0]",
        "position = [0.0, 0.0, 0.0, 5.0]",
        "camera.position",
        "",
        V3,
    ),
    c(
        "look_at = [0.0, 0.0, -1.0]",
        "look_at = [0, 0, -1, \"junk\"]",
        "camera.look_at",
        "",
        V3,
    ),
    c(
        "up = [0.0, 1.0, 0.0]",
        "up = [0.0, 1.0]",
        "camera.up",
        "",
        V3,
    ),
    c(
        "position = [0.0, 0.0, 0.0]",
        "position = \"origin\"",
        "camera.position",
        "",
        V3,
    ),
    c(
        "position = [0.0, 0.0, 0.0]",
        "position = [0.0, \"x\", 0.0]",
        "camera.position[1]",
        "",
        "in [-1e9, 1e9]",
    ),
    c(
        "direction = [-0.45, 0.65, 0.6]",
        "direction = [1, 2]",
        "light[0].direction",
        "",
        V3,
    ),
    c(
        "axis = [0.0, 1.0, 0.8]",
        "axis = 1.0",
        "object[1].axis",
        "",
        V3,
    ),
    c(
        "vertices = [[1.0, 1.0, 0.5], [30.0, 2.0, 0.5], [2.0, 30.0, 0.5]]",
        "vertices = [[1.0, 1.0, 0.5], [30.0, 2.0], [2.0, 30.0, 0.5]]",
        "object[3].vertices[1]",
        "",
        V3,
    ),
    c(
        "vertices = [[1.0, 1.0, 0.5], [30.0, 2.0, 0.5], [2.0, 30.0, 0.5]]",
        "vertices = \"tri\"",
        "object[3].vertices",
        "",
        "3 (triangle) or 4 (quad) vertices",
    ),
    c(
        "vertices = [[1.0, 1.0, 0.5], [30.0, 2.0, 0.5], [2.0, 30.0, 0.5]]",
        "vertices = [[1.0, 1.0, 0.5], [30.0, 2.0, 0.5]]",
        "object[3].vertices",
        "",
        "an array of 3 vertices",
    ),
    c(
        "intensity = [0.2, 0.4, 0.6]",
        "intensity = [0.2, 0.4]",
        "object[3].intensity",
        "",
        "an array of 3 intensities (one per vertex)",
    ),
    c(
        "intensity = [0.2, 0.4, 0.6]",
        "intensity = [0.2, \"x\", 0.6]",
        "object[3].intensity[1]",
        "",
        "in [0, 1e6]",
    ),
    // Wrong table kinds.
    c("[image]", "[[image]]", "image", "", "a table [image]"),
    c(
        "[camera.lens]",
        "[[camera.lens]]",
        "camera.lens",
        "",
        "a table [camera.lens]",
    ),
    c("[[light]]", "[light]", "light", "", "[[light]]"),
    d(
        "[shading]\nambient = 0.08\n",
        "name = \"m\"",
        "name = \"m\"\nshading = 0.1",
        "shading",
        "shading = 0.1",
        "a table [shading]",
    ),
    d(
        LIGHT,
        "name = \"m\"",
        "name = \"m\"\nlight = 5",
        "light",
        "light = 5",
        "an array of tables",
    ),
    d(
        LIGHT,
        "name = \"m\"",
        "name = \"m\"\nlight = { direction = [0, 1, 0] }",
        "light",
        "light = {",
        "got an inline table",
    ),
    c(
        "[[object]]\nkind = \"cylinder\"",
        "[object]\nkind = \"cylinder\"",
        "object",
        "",
        "an array of tables",
    ),
    // Duplicate keys and tables.
    c(
        "width = 64",
        "width = 64\nwidth = 65",
        "image.width",
        "width = 65",
        "line 3",
    ),
    c(
        "radius = 0.6",
        "radius = 0.6\nradius = 0.7",
        "object[2].radius",
        "radius = 0.7",
        "given twice",
    ),
    c(
        "kind = \"thin_lens\"",
        "kind = \"thin_lens\"\nkind = \"pinhole\"",
        "camera.lens.kind",
        "kind = \"pinhole\"",
        "given twice",
    ),
    c(
        "[shading]",
        "[display] # again",
        "display",
        "",
        "first at line 23",
    ),
    // Unknown keys.
    c(
        "height = 48",
        "height = 48\ndepth = 3",
        "image.depth",
        "depth",
        "allowed: `width`, `height`, `background`",
    ),
    c(
        "minor_radius = 0.8",
        "minor_radius = 0.8\nradiuss = 2",
        "object[1].radiuss",
        "radiuss",
        "allowed:",
    ),
    c("[shading]", "[lighting]", "lighting", "", "allowed:"),
    c(
        "coc = 0.000035",
        "coc = 0.000035\naperture = 2",
        "camera.lens.aperture",
        "aperture",
        "allowed:",
    ),
    // Truncated files.
    cut(
        "position = [0.0, 0.0, 0.0]",
        "position = [0.0, 0",
        "camera.position",
        "",
        V3,
    ),
    cut(
        "width = 64",
        "width = ",
        "image.width",
        "",
        "an integer in 1..=8192",
    ),
    cut(
        "[[object]]\nkind = \"torus\"",
        "[[object",
        "object[1]",
        "",
        "an array of tables",
    ),
    cut(
        "[camera]",
        "[camera]\n",
        "camera.position",
        "[camera]",
        "required",
    ),
    cut(
        "[image]",
        "[image]\nwidth = 64\nheight = 48\n",
        "camera",
        "name",
        "a table [camera]",
    ),
    cut(
        "kind = \"line\"",
        "kind = \"line\"\nfrom = [-1.0, 1.0, -8.0]\nto = [1.0, 1.5",
        "object[5].to",
        "to =",
        V3,
    ),
    // Out-of-range numbers: the accepted garbage of issue 13 and unbounded loops.
    c(
        "lens_radius = 0.06",
        "lens_radius = 1e308",
        "camera.lens.lens_radius",
        "",
        LEN,
    ),
    c(
        "lens_radius = 0.06",
        "lens_radius = 1e50",
        "camera.lens.lens_radius",
        "",
        LEN,
    ),
    c(
        "lens_radius = 0.06",
        "lens_radius = 5.0",
        "camera.lens.lens_radius",
        "",
        "camera.near = 2",
    ),
    c(
        "lens_radius = 0.06",
        "f_number = 1e-308",
        "camera.lens.f_number",
        "",
        "in [0.001, 1e6]",
    ),
    c(
        "lens_radius = 0.06",
        "f_number = 0.001",
        "camera.lens.f_number",
        "",
        "f_number must be >= focal_length / (2 camera.near) = 0.005",
    ),
    c(
        "width = 1.5",
        "width = 1e308",
        "object[5].width",
        "",
        "in (0, 16544] pixels",
    ),
    c(
        "size = 1.0",
        "size = 1e308",
        "object[6].size",
        "",
        "in (0, 16544] pixels",
    ),
    c(
        "tessellation = 16",
        "tessellation = 100000",
        "object[0].tessellation",
        "",
        "3..=1024",
    ),
    c("near = 2.0", "near = 1e-300", "camera.near", "", LEN),
    c(
        "fov_y_deg = 40.0",
        "fov_y_deg = 1e-300",
        "camera.fov_y_deg",
        "",
        "in [0.001, 180)",
    ),
    c(
        "contrast = 100.0",
        "contrast = 1.0000000001",
        "display.contrast",
        "",
        "in [2, 1e9]",
    ),
    c(
        "weber = 0.02",
        "weber = 1e-300",
        "display.weber",
        "",
        "in [0.001, 0.5]",
    ),
    c(
        "refresh_hz = 60.0",
        "refresh_hz = 1e-300",
        "display.refresh_hz",
        "",
        "in [1, 1000]",
    ),
    c(
        "center = [0.3, 0.0, -10.0]",
        "center = [0.3, 0.0, -1e300]",
        "object[0].center[2]",
        "",
        "in [-1e9, 1e9]",
    ),
    c(
        "position = [0.0, 0.0, 0.0]",
        "position = [1e300, 0.0, 0.0]",
        "camera.position[0]",
        "",
        "in [-1e9, 1e9]",
    ),
    c(
        "radius = 1.8",
        "radius = nan",
        "object[0].radius",
        "",
        "got NaN",
    ),
    c(
        "intensity = 1.0",
        "intensity = inf",
        "object[5].intensity",
        "",
        "in [0, 1e6]",
    ),
    c(
        "shininess = 30.0",
        "shininess = 1e308",
        "object[0].shininess",
        "",
        "in (0, 1e6]",
    ),
    c(
        "deep = 1.8",
        "deep = -1",
        "camera.lens.deep",
        "",
        "in [0, 1e9]",
    ),
];

const HW_CASES: &[Case] = &[
    c(
        "weight_bits = 10",
        "weight_bits = \"64\"",
        "accumulate.weight_bits",
        "",
        "..=16",
    ),
    c(
        "weight_bits = 10",
        "weight_bits = -1",
        "accumulate.weight_bits",
        "",
        "..=16",
    ),
    c(
        "weight_bits = 10",
        "weight_bits = 99",
        "accumulate.weight_bits",
        "",
        "..=16",
    ),
    c(
        "gaussian_sigma = 0.5",
        "gaussian_sigma = \"0.5\"",
        "accumulate.gaussian_sigma",
        "",
        "[0.1, 2.0]",
    ),
    c(
        "gaussian_sigma = 0.5",
        "gaussian_sigma = nan",
        "accumulate.gaussian_sigma",
        "",
        "0.1..=2.0",
    ),
    c(
        "filter = \"tent\"",
        "filter = \"sinc\"",
        "accumulate.filter",
        "",
        "allowed: `box`, `tent`, `gaussian`",
    ),
    c(
        "frame = \"UQ12.0\"",
        "frame = 12",
        "accumulate.frame",
        "",
        "UQ<int>.<frac>",
    ),
    c(
        "frame = \"UQ12.0\"",
        "frame = \"UQ40.0\"",
        "accumulate.frame",
        "",
        "1..=32",
    ),
    c(
        "[accumulate]",
        "[[accumulate]]",
        "accumulate",
        "",
        "a table [accumulate]",
    ),
    c(
        "correction = true",
        "correction = \"yes\"",
        "gamma.correction",
        "",
        "true or false",
    ),
    c(
        "dac_bits = 8",
        "dac_bits = 0",
        "gamma.dac_bits",
        "",
        "1..=16",
    ),
    c(
        "clock_mhz = 100.0",
        "clock_mhz = \"fast\"",
        "cycles.clock_mhz",
        "",
        "[0.001, 10000]",
    ),
    c(
        "clock_mhz = 100.0",
        "clock_mhz = 1e-300",
        "cycles.clock_mhz",
        "",
        "[0.001, 10000]",
    ),
    c(
        "lanes = 4",
        "lanes = \"4\"",
        "cycles.raster.lanes",
        "",
        "1..=1024",
    ),
    c(
        "[cycles.raster]",
        "[cycles.rasterx]",
        "cycles.rasterx",
        "",
        "allowed:",
    ),
    d(
        "[cycles.raster]\nlanes = 4\n",
        "tile = 16",
        "tile = 16\nraster = 4",
        "cycles.raster",
        "raster = 4",
        "a table [cycles.raster]",
    ),
    c(
        "samples = 4",
        "samples = 3",
        "raster.samples",
        "",
        "1, 2, 4 or 8",
    ),
    c(
        "samples = 4",
        "samples = \"4\"",
        "raster.samples",
        "",
        "1, 2, 4 or 8",
    ),
    c(
        "guard_band = 64",
        "guard_band = 1e9",
        "raster.guard_band",
        "",
        "0..=4096",
    ),
    c(
        "quant = \"RND_CONV\"",
        "quant = \"RND_X\"",
        "input.quant",
        "",
        "allowed:",
    ),
    c(
        "coord = \"Q13.4\"",
        "coord = 13",
        "input.coord",
        "",
        "Q<int>.<frac>",
    ),
    c(
        "preset = \"linear12\"",
        "preset = 12",
        "preset",
        "",
        "\"linear12\"",
    ),
    c(
        "preset = \"linear12\"",
        "preset = \"linear99\"",
        "preset",
        "",
        "linear12",
    ),
    c("p = 0.1", "p = nan", "dof.p", "", "(0, 1)"),
    c(
        "kind = \"layered\"",
        "kind = \"gaussian\"",
        "dof.kind",
        "",
        "allowed: `layered`, `luminance`, `downsample`",
    ),
    c(
        "sigma = \"paper\"",
        "sigma = 3",
        "dof.sigma",
        "",
        "\"paper\", \"affine\"",
    ),
    c(
        "sigma_rom_bits = 10",
        "sigma_rom_bits = 30",
        "dof.sigma_rom_bits",
        "",
        "4..=16",
    ),
    c(
        "max_half_size = 32",
        "max_half_size = 1000",
        "dof.max_half_size",
        "",
        "1..=64",
    ),
    c(
        "frac_bits = 4",
        "frac_bits = 99",
        "dither.frac_bits",
        "",
        "1..=8",
    ),
    c(
        "kind = \"none\"",
        "kind = \"bayer3\"",
        "dither.kind",
        "",
        "allowed:",
    ),
    c(
        "log_bits = 8",
        "log_bits = 99999999999",
        "coding.log_bits",
        "",
        "3..=12",
    ),
    c(
        "p = 0.1",
        "p = 0.1\np = 0.2",
        "dof.p",
        "p = 0.2",
        "given twice",
    ),
    c(
        "[cycles]",
        "[ gamma ]",
        "gamma",
        "",
        "duplicate table: [gamma] is given twice (first at line 21)",
    ),
    cut(
        "guard_band = 64",
        "guard_band = ",
        "raster.guard_band",
        "",
        "0..=4096",
    ),
    cut("[cycles]", "[cycles", "cycles", "", "a table [cycles]"),
    c("[coding]", "[foo]", "foo", "", "allowed:"),
    d(
        "[gamma]\ndac_bits = 8\ncorrection = true\n",
        "preset = \"linear12\"",
        "preset = \"linear12\"\ngamma = 2.2",
        "gamma",
        "gamma = 2.2",
        "a table [gamma]",
    ),
    c(
        "interpolate = false",
        "interpolate = 1",
        "coding.interpolate",
        "",
        "true or false",
    ),
    c(
        "max_half_size = 32",
        "max_half_size = 2.5",
        "dof.max_half_size",
        "",
        "1..=64",
    ),
];

/// The mutated text of a case.
fn text(base: &str, case: &Case) -> String {
    let base = &if case.drop.is_empty() {
        base.to_string()
    } else {
        assert_eq!(base.matches(case.drop).count(), 1, "{}", case.drop);
        base.replacen(case.drop, "", 1)
    };
    assert_eq!(
        base.matches(case.from).count(),
        1,
        "`{}` must occur once in the base",
        case.from
    );
    let start = base.find(case.from).expect("in the base");
    let mut t = base.replacen(case.from, case.to, 1);
    if case.cut > 0 {
        t.truncate(start + case.to.len() + case.cut - 1);
    }
    t
}

/// 1-based line of the first line that is `needle`, else of the first containing it.
fn line_of(text: &str, needle: &str) -> usize {
    text.lines()
        .position(|l| l.trim() == needle)
        .or_else(|| text.lines().position(|l| l.contains(needle)))
        .unwrap_or_else(|| panic!("`{needle}` not in the text"))
        + 1
}

fn check(kind: &str, name: &str, text: &str, case: &Case, e: &FileError) {
    let at = if case.at.is_empty() {
        case.to.lines().next().unwrap_or(case.to)
    } else {
        case.at
    };
    let ctx = format!("{kind} case `{}` -> `{}`: {e}", case.from, case.to);
    assert_eq!(e.file, name, "{ctx}");
    assert_eq!(e.field, case.field, "{ctx}");
    assert_eq!(e.line, Some(line_of(text, at)), "{ctx}");
    assert!(e.col.is_some(), "{ctx}");
    assert!(e.msg.contains(case.hint), "{ctx}: no `{}`", case.hint);
    let shown = e.to_string();
    assert!(
        shown.starts_with(&format!("{name}:{}:", e.line.unwrap())),
        "{ctx}"
    );
    assert!(shown.contains(&format!("field `{}`", case.field)), "{ctx}");
}

#[test]
fn the_bases_are_valid() {
    let s = Scene::from_toml(&TomlFile::from_text("m.toml", SCENE)).unwrap();
    assert_eq!(s.objects.len(), 8);
    HwConfig::from_toml(&TomlFile::from_text("h.toml", HW)).unwrap();
}

#[test]
fn every_malformed_scene_names_file_line_field_and_expected() {
    assert!(SCENE_CASES.len() + HW_CASES.len() >= 60);
    for case in SCENE_CASES {
        let t = text(SCENE, case);
        let e = Scene::from_toml(&TomlFile::from_text("m.toml", &t))
            .err()
            .unwrap_or_else(|| panic!("accepted: `{}`", case.to));
        check("scene", "m.toml", &t, case, &e);
    }
}

#[test]
fn every_malformed_hardware_file_names_file_line_field_and_expected() {
    for case in HW_CASES {
        let t = text(HW, case);
        let e = HwConfig::from_toml(&TomlFile::from_text("h.toml", &t))
            .err()
            .unwrap_or_else(|| panic!("accepted: `{}`", case.to));
        check("hardware", "h.toml", &t, case, &e);
    }
}

/// The binary exits 2 with the library's message for every case (no panic).
#[test]
fn the_binary_exits_2_with_the_message() {
    let dir = std::env::temp_dir().join(format!("igemu-messages-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let out = dir.join("o.png");
    let out = out.to_str().unwrap();
    let cases = SCENE_CASES
        .iter()
        .map(|c| (true, c))
        .chain(HW_CASES.iter().map(|c| (false, c)));
    for (k, (is_scene, case)) in cases.enumerate() {
        let path = dir.join(format!("case{k}.toml"));
        let p = path.to_str().unwrap();
        let t = text(if is_scene { SCENE } else { HW }, case);
        std::fs::write(&path, &t).unwrap();
        let file = TomlFile::from_text(p, &t);
        let e = if is_scene {
            Scene::from_toml(&file).err()
        } else {
            HwConfig::from_toml(&file).err()
        }
        .expect("refused");
        let args = if is_scene {
            vec!["render", p, "--no-local", "-o", out]
        } else {
            vec!["render", "--hw", p, "--no-local", "-o", out]
        };
        let (code, stdout, stderr) = common::igemu(&args);
        assert_eq!(code, 2, "`{}`: {stdout} {stderr}", case.to);
        assert!(!stderr.contains("panicked"), "{stderr}");
        assert!(stderr.contains(&e.to_string()), "`{e}` not in {stderr}");
    }
    assert!(!std::path::Path::new(out).exists(), "nothing is written");
    std::fs::remove_dir_all(&dir).unwrap();
}

/// The hints the TOML layer names are the ranges the validation applies: a value just outside
/// each range is refused with the same range in the message.
#[test]
fn hints_and_validation_agree() {
    for (path, bad, range) in [
        ("image.width", "width = 8193", "1..=8192"),
        ("object[0].tessellation", "tessellation = 2", "3..=1024"),
        ("camera.near", "near = 1e-10", "[1e-9, 1e9]"),
        ("display.weber", "weber = 0.6", "[0.001, 0.5]"),
    ] {
        let hint = Scene::field_hint(path).unwrap();
        assert!(hint.contains(range), "{path}: {hint}");
        let from = bad.split('=').next().unwrap().trim();
        let line = SCENE
            .lines()
            .find(|l| l.starts_with(&format!("{from} =")))
            .unwrap();
        let t = SCENE.replacen(line, bad, 1);
        let e = Scene::from_toml(&TomlFile::from_text("m.toml", &t)).unwrap_err();
        assert_eq!(e.field, path, "{e}");
        assert!(e.msg.contains(range), "{e}");
    }
    for (path, bad, range) in [
        ("gamma.dac_bits", "dac_bits = 17", "1..=16"),
        ("raster.guard_band", "guard_band = 4097", "0..=4096"),
        ("cycles.tile", "tile = 512", "4..=256"),
        ("coding.log_bits", "log_bits = 2", "3..=12"),
        ("dither.frac_bits", "frac_bits = 0", "1..=8"),
        ("dof.max_half_size", "max_half_size = 65", "1..=64"),
        ("dof.sigma_rom_bits", "sigma_rom_bits = 17", "4..=16"),
    ] {
        let hint = HwConfig::field_hint(path).unwrap();
        assert!(hint.contains(range), "{path}: {hint}");
        let from = bad.split('=').next().unwrap().trim();
        let line = HW
            .lines()
            .find(|l| l.starts_with(&format!("{from} =")))
            .unwrap();
        let t = HW.replacen(line, bad, 1);
        let e = HwConfig::from_toml(&TomlFile::from_text("h.toml", &t)).unwrap_err();
        assert_eq!(e.field, path, "{e}");
        assert!(e.msg.contains(range), "{e}");
    }
    assert!(Scene::field_hint("object[3].nothing").is_none());
    assert!(HwConfig::field_hint("cycles.nothing.lanes").is_none());
}

/// Every number of a hardware file has a finite range: NaN, infinities, huge and negative
/// values are refused with the field's name, for every real and every integer field (the
/// dither's seed and frame number take any value of their type).
#[test]
fn hardware_numbers_refuse_nan_inf_and_values_out_of_range() {
    let reals = [
        ("accumulate", "gaussian_sigma"),
        ("gamma", "gamma"),
        ("cycles", "clock_mhz"),
        ("dof", "p"),
        ("dof", "k"),
    ];
    let mut integers: Vec<(String, &str)> = [
        ("raster", "samples"),
        ("raster", "interp_guard_bits"),
        ("raster", "guard_band"),
        ("accumulate", "weight_bits"),
        ("gamma", "dac_bits"),
        ("cycles", "tile"),
        ("cycles", "frame_port_bits"),
        ("dither", "frac_bits"),
        ("dither", "blue_noise_size"),
        ("dof", "coef_bits"),
        ("dof", "alpha_bits"),
        ("dof", "guard_bits"),
        ("dof", "line_bits"),
        ("dof", "acc_bits"),
        ("dof", "max_half_size"),
        ("coding", "log_bits"),
        ("coding", "acc_frac_bits"),
        ("coding", "table_addr_bits"),
        ("coding", "table_frac_bits"),
    ]
    .into_iter()
    .map(|(s, f)| (s.to_string(), f))
    .collect();
    for stage in igemu::config::TIMED {
        for (f, _, _) in igemu::config::TIMING_RANGES {
            integers.push((format!("cycles.{}", stage.name()), f));
        }
    }
    let refused = |section: &str, field: &str, value: &str| {
        let text = format!("[{section}]\n{field} = {value}\n");
        let e = HwConfig::from_toml(&TomlFile::from_text("h.toml", &text))
            .err()
            .unwrap_or_else(|| panic!("accepted: {text}"));
        assert_eq!(e.field, format!("{section}.{field}"), "{text}: {e}");
        assert_eq!(e.line, Some(2), "{e}");
        let hint = HwConfig::field_hint(&e.field).expect("every field has a hint");
        assert!(
            e.msg.contains("must be") || e.msg.contains(&hint),
            "{text}: {e}"
        );
    };
    for (section, field) in reals {
        for v in ["nan", "inf", "-inf", "1e308", "-1e308", "0", "\"1\""] {
            refused(section, field, v);
        }
    }
    for (section, field) in &integers {
        for v in [
            "4294967295",
            "4294967296",
            "-1",
            "1.5",
            "nan",
            "\"8\"",
            "[8]",
        ] {
            refused(section, field, v);
        }
    }
    // The seed and the frame number take any value of their type, and nothing else.
    for (field, max) in [("seed", "18446744073709551615"), ("frame", "4294967295")] {
        let text = format!("[dither]\n{field} = {max}\n");
        HwConfig::from_toml(&TomlFile::from_text("h.toml", &text)).unwrap();
        for v in ["-1", "1.5", "nan", "\"1\""] {
            refused("dither", field, v);
        }
    }
}

/// Every number of a scene has a finite range: each number of the base scene (a scalar or
/// an element of a vector) replaced by NaN, an infinity or ±1e308 is refused, naming that
/// field.
#[test]
fn scene_numbers_refuse_nan_inf_and_huge_values() {
    let (mut table, mut objects, mut lights) = (String::new(), 0, 0);
    let mut checked = 0;
    for (k, line) in SCENE.lines().enumerate() {
        if line == "[[object]]" {
            table = format!("object[{objects}]");
            objects += 1;
            continue;
        }
        if line == "[[light]]" {
            table = format!("light[{lights}]");
            lights += 1;
            continue;
        }
        if let Some(h) = line.strip_prefix('[') {
            table = h.trim_end_matches(']').to_string();
            continue;
        }
        let Some((key, value)) = line.split_once(" = ") else {
            continue;
        };
        let path = format!("{table}.{key}");
        let mut lines: Vec<String> = SCENE.lines().map(String::from).collect();
        let mut try_value = |field: &str, new: String| {
            lines[k] = new;
            let text = lines.join("\n");
            let e = Scene::from_toml(&TomlFile::from_text("m.toml", &text))
                .err()
                .unwrap_or_else(|| panic!("accepted: {}", lines[k]));
            assert_eq!(e.field, field, "{}: {e}", lines[k]);
            assert_eq!(e.line, Some(k + 1), "{e}");
            checked += 1;
        };
        for bad in ["nan", "inf", "-inf", "1e308", "-1e308"] {
            if value.parse::<f64>().is_ok() {
                try_value(&path, format!("{key} = {bad}"));
            } else if value.starts_with('[') && !value.starts_with("[[") {
                let n = value.matches(',').count() + 1;
                for i in 0..n {
                    let mut xs: Vec<String> = value
                        .trim_matches(['[', ']'])
                        .split(", ")
                        .map(String::from)
                        .collect();
                    xs[i] = bad.to_string();
                    try_value(
                        &format!("{path}[{i}]"),
                        format!("{key} = [{}]", xs.join(", ")),
                    );
                }
            }
        }
    }
    assert!(checked > 200, "{checked}");
}

/// A file cut at any byte is refused without a panic, naming a field and a line (or, cut at a
/// line that leaves a valid file, accepted).
#[test]
fn files_cut_anywhere_name_a_field_and_a_line() {
    for (base, is_scene) in [(SCENE, true), (HW, false)] {
        let mut refused = 0;
        for end in (0..base.len()).filter(|&i| base.is_char_boundary(i)) {
            let t = &base[..end];
            let file = TomlFile::from_text("cut.toml", t);
            let e = if is_scene {
                Scene::from_toml(&file).err()
            } else {
                HwConfig::from_toml(&file).err()
            };
            if let Some(e) = e {
                refused += 1;
                assert!(!e.field.is_empty(), "cut at {end}: {e}");
                assert!(e.line.is_some() && e.col.is_some(), "cut at {end}: {e}");
                assert!(e.to_string().starts_with("cut.toml:"), "cut at {end}: {e}");
            }
        }
        assert!(refused > base.len() / 2, "{refused}");
    }
}

/// A negative number given to a count or a size is refused naming the option and its range
/// (clap read `-8` as a flag: "unexpected argument '-8' found"), before any work.
#[test]
fn negative_numbers_name_the_option_and_its_range() {
    let dir = std::env::temp_dir().join(format!("igemu-negative-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let out = dir.join("o.png");
    let o = out.to_str().unwrap();
    let grid = "examples/grid.toml";
    let cases: &[(&[&str], &str)] = &[
        (
            &["render", "--dof-truth", "--lens-samples", "-8", "-o", o],
            "'--lens-samples <N>': must be a multiple of 8 (the noise estimate's interleaved groups) in 8..=4096, got -8",
        ),
        (
            &["render", "--max-memory", "-1", "-o", o],
            "'--max-memory <SIZE>': `-1` must be at least 1 byte",
        ),
        (
            &["render", "--max-memory", "-1G", "-o", o],
            "'--max-memory <SIZE>': `-1G` must be at least 1 byte",
        ),
        (
            &["check", "--max-code-diff", "-1"],
            "'--max-code-diff <N>': must be an integer in 0..=65535, got -1",
        ),
        (
            &["sweep", "--grid", grid, "--out", o, "--jobs", "-1"],
            "'--jobs <JOBS>': must be an integer in 1..=1024, got -1",
        ),
        (
            &["sweep", "--grid", grid, "--out", o, "--flicker", "-3"],
            "'--flicker <PHASES>': must be an integer in 2..=64, got -3",
        ),
        (
            &["flicker", "--phases", "-3"],
            "'--phases <PHASES>': must be an integer in 2..=64, got -3",
        ),
    ];
    for (args, msg) in cases {
        let (code, stdout, stderr) = common::igemu(args);
        assert_eq!(code, 2, "{args:?}: {stdout}{stderr}");
        assert!(stderr.contains(msg), "{args:?}: {stderr}");
        assert!(
            !stderr.contains("unexpected argument"),
            "{args:?}: {stderr}"
        );
    }
    assert!(!out.exists(), "nothing is written");
    std::fs::remove_dir_all(&dir).unwrap();
}

/// A check across fields or files (the screen against the coordinate format, a grid key)
/// names each field with the file and line its value comes from (or the preset), says the
/// fix, and exits 2 before any output is written.
#[test]
fn cross_field_refusals_name_each_file_and_line() {
    let dir = std::env::temp_dir().join(format!("igemu-cross-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let put = |name: &str, text: &str| {
        let p = dir.join(name);
        std::fs::write(&p, text).unwrap();
        p.to_str().unwrap().to_string()
    };
    let big_text = "[image]\nwidth = 8192\nheight = 8192\n[camera]\nposition = [0, 0, 5]\nlook_at = [0, 0, 0]\nnear = 0.1\nfar = 100\n";
    let big = put("big.toml", big_text);
    let narrow = put(
        "hw.toml",
        "preset = \"linear12\"\n[input]\ncoord = \"Q3.12\"\n[raster]\nguard_band = 4096\n",
    );
    let newline = put("g.toml", "[gamma]\n\"dac\\nbits\" = [8, 9]\n");
    let grid = put("ok-grid.toml", "gamma.dac_bits = [8, 9]\n");
    let out = dir.join("o.png");
    let csv = dir.join("s.jsonl");
    let (o, c) = (out.to_str().unwrap(), csv.to_str().unwrap());
    let cases: Vec<(Vec<&str>, Vec<String>)> = vec![
        (
            vec!["render", &big, "-o", o],
            vec![
                format!("{big}:2:1: field `image.width`"),
                format!("(image.width, {big}:2)"),
                "(raster.guard_band, preset linear12)".into(),
                "input.coord = Q13.4 (preset linear12)".into(),
                "needs coordinates up to 8257 px".into(),
                "--hw examples/q15-4.toml".into(),
                "1..=4030".into(),
            ],
        ),
        (
            vec!["render", "--hw", &narrow, "-o", o],
            vec![
                format!("{narrow}:3:1: field `input.coord`"),
                format!("(raster.guard_band, {narrow}:5)"),
                format!("input.coord = Q3.12 ({narrow}:3)"),
                format!("e.g. input.coord = \"Q14.12\" in {narrow}"),
            ],
        ),
        (
            vec!["sweep", "--grid", &newline, "--out", c, "default"],
            vec![
                format!("{newline}:2:1: field `gamma.dac\\nbits`"),
                "is not a hardware field name".into(),
            ],
        ),
        (
            vec!["sweep", "--grid", &grid, "--out", c, &big],
            vec![
                format!("{big}:2:1: field `image.width`"),
                "configuration 0 (gamma.dac_bits=8) on scene `big`".into(),
            ],
        ),
    ];
    for (args, wants) in &cases {
        let (code, stdout, stderr) = common::igemu(args);
        assert_eq!(code, 2, "{args:?}: {stdout}{stderr}");
        for w in wants {
            assert!(
                stderr.contains(w.as_str()),
                "{args:?}: want {w:?} in {stderr}"
            );
        }
        assert!(
            !out.exists() && !csv.exists(),
            "{args:?}: nothing is written"
        );
    }
    // The fix the message names holds the screen.
    let scene = Scene::from_toml(&TomlFile::from_text("big.toml", big_text)).unwrap();
    let wide = HwConfig::from_toml(&TomlFile::read("examples/q15-4.toml").unwrap()).unwrap();
    assert!(igemu::pipeline::guard_band(&scene, &wide).is_ok());
    assert!(igemu::pipeline::guard_band(&scene, &HwConfig::preset("linear12").unwrap()).is_err());
    std::fs::remove_dir_all(&dir).unwrap();
}
