#!/usr/bin/env python3
"""The DoF comparison table of docs/dof-compare.md: every dof.kind on three scenes against
the accumulation-buffer truth. Usage (from the repository root, after `cargo build --release`):

    python3 examples/dof_compare.py [--igemu target/release/igemu] [--lens-samples N]

Runs `igemu render SCENE --hw KIND.toml --dof-truth --lens-samples N --json` for each
scene and kind (and the downsample method's cubic reconstructions; `--reconstruction-only`
runs only those) and prints one Markdown table row per run: the errors against the truth
(algorithm: float method vs truth; quantisation: fixed vs float method; total) as RMS in
8-bit DAC codes over the whole image, the depth-edge band and the interior, the truth's own
noise (RMS standard error, DAC codes), the dof stage's MACs, its RAM + ROM bits, the cycle
model's frame cycles and the dof stage's busy cycles, and the emulator's dof time (fixed and
float, ms; one run on a shared machine)."""

import argparse
import json
import os
import subprocess
import sys
import tempfile

SCENES = ["default", "cone-focus", "examples/depth-ramp.toml"]
# (dof.kind, dof.kernel): the layered method with each kernel, the downsample method with
# the paper's Gaussian and the disc-fitted copy (the luminance method has no kernel).
KINDS = [("layered", "gaussian"), ("layered", "disc"), ("layered", "fitted_gaussian"),
         ("luminance", "gaussian"), ("downsample", "gaussian"),
         ("downsample", "fitted_gaussian")]
# The downsample method's cubic reconstructions (dof.downsample.reconstruction; bilinear in
# the rows above), with the fitted kernel.
RECONSTRUCTIONS = [("downsample", "fitted_gaussian", r)
                   for r in ["cubic_bspline", "catmull_rom", "mitchell"]]


def render(igemu, scene, kind, n, tmp):
    kind, kernel, recon = (kind + ("bilinear",))[:3]
    hw = os.path.join(tmp, f"{kind}-{kernel}-{recon}.toml")
    with open(hw, "w") as f:
        f.write(f'[dof]\nkind = "{kind}"\nkernel = "{kernel}"\n'
                f'[dof.downsample]\nreconstruction = "{recon}"\n')
    out = os.path.join(tmp, "out.png")
    cmd = [igemu, "render", scene, "--hw", hw, "--dof-truth", "--lens-samples", str(n),
           "--json", "-o", out]
    p = subprocess.run(cmd, capture_output=True, text=True)
    if p.returncode != 0:
        sys.exit(f"{' '.join(cmd)}: exit {p.returncode}\n{p.stderr}")
    return json.loads(p.stdout)


def row(scene, kind, r):
    t = r["dof_truth"]
    dof = next(s for s in r["stages"] if s["name"] == "dof")
    busy = next(s["busy"] for s in r["cycles"]["stages"] if s["name"] == "dof")
    rms = lambda split: "{:.2f} / {:.2f} / {:.2f}".format(
        split["whole"]["rms"], split["edge"]["rms"], split["interior"]["rms"])
    return "| {} | {} | {} | {} | {} | {:.3f} | {:.1f} M | {} | {} / {} | {:.0f} / {:.0f} |".format(
        os.path.basename(scene).removesuffix(".toml"),
        kind[0] if kind[0] == "luminance" else " / ".join(kind),
        rms(t["algorithm"]), rms(t["quantisation"]), rms(t["total"]),
        t["noise"]["dac"]["whole"]["rms"],
        dof["work"].get("macs", 0) / 1e6,
        dof["cost"]["storage_bits"] + dof["cost"]["lut_bits"],
        r["cycles"]["total_cycles"], busy,
        dof["fixed_ms"], dof["float_ms"])


def main():
    a = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    a.add_argument("--igemu", default="target/release/igemu")
    a.add_argument("--lens-samples", type=int, default=256)
    a.add_argument("--reconstruction-only", action="store_true",
                   help="only the downsample method's cubic reconstruction rows")
    args = a.parse_args()
    kinds = RECONSTRUCTIONS if args.reconstruction_only else KINDS + RECONSTRUCTIONS
    print("| scene | dof.kind / kernel | algorithm RMS (whole / edge / interior) | quantisation RMS | "
          "total RMS | truth noise RMS | MACs | RAM + ROM bits | frame / dof busy cycles | "
          "dof fixed / float ms |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    with tempfile.TemporaryDirectory() as tmp:
        for scene in SCENES:
            for kind in kinds:
                print(row(scene, kind, render(args.igemu, scene, kind, args.lens_samples, tmp)),
                      flush=True)


if __name__ == "__main__":
    main()
