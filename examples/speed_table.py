#!/usr/bin/env python3
"""The bench table of docs/speed.md: every speed figure of the emulator as a ratio measured
within one run. Usage (from the repository root):

    cargo build --release && python3 examples/speed_table.py [--runs 3] [--no-bench]

Prints Markdown: per scene the fixed model against its float reference (whole pipeline and
per stage, from `igemu render SCENE --json --no-local`), the layered DoF against the
per-pixel scatter (`igemu render SCENE --dof-reference --json`), the cycle simulator's
simulated cycles per second (`igemu cycles --json`), the sweep's stage reuse (`igemu sweep`
with and without `--no-reuse`, the same grid) and, unless `--no-bench`, the gamma LUT +
ordered dither against a plain copy (`cargo bench --bench dither`, its ratio lines).

Each render figure is the run with the median fixed/float ratio of `--runs` runs (the
machine is shared and noisy: a ratio within one run is what compares)."""

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time

SCENES = ["default", "default-pinhole", "cone-focus"]


def run(cmd):
    p = subprocess.run(cmd, capture_output=True, text=True)
    if p.returncode != 0:
        sys.exit(f"{' '.join(cmd)}: exit {p.returncode}\n{p.stderr}")
    return p.stdout


def render(igemu, scene, tmp, extra=()):
    out = os.path.join(tmp, "out.png")
    return json.loads(run([igemu, "render", scene, "--json", "-o", out, *extra]))


def median_run(runs, key):
    runs = sorted(runs, key=key)
    return runs[len(runs) // 2]


def pipeline_table(igemu, runs, tmp):
    print(
        "| scene | fixed ms | float ms | fixed / float | all runs: min-max, runs with fixed <= float "
        "| per stage: fixed / float ms |"
    )
    print("|---|---|---|---|---|---|")
    ratio = lambda r: r["timing"]["fixed_ms"] / r["timing"]["float_ms"]
    for scene in SCENES:
        rs = [render(igemu, scene, tmp, ["--no-local"]) for _ in range(runs)]
        r = median_run(rs, ratio)
        t = r["timing"]
        stages = ", ".join(
            f"{s['name']} {s['fixed_ms']:.1f} / {s['float_ms']:.1f}" for s in r["stages"]
        )
        rr = [ratio(x) for x in rs]
        held = sum(x <= 1.0 for x in rr)
        print(
            f"| {scene} | {t['fixed_ms']:.1f} | {t['float_ms']:.1f} | {ratio(r):.2f} | "
            f"{min(rr):.2f}-{max(rr):.2f}, {held} of {runs} | {stages} |"
        )


def dof_table(igemu, runs, tmp):
    print("| scene | fixed layered DoF ms | per-pixel scatter ms | per-pixel / fixed |")
    print("|---|---|---|---|")
    for scene in ["default", "cone-focus"]:
        rows = []
        for _ in range(runs):
            r = render(igemu, scene, tmp, ["--no-local", "--dof-reference"])
            d = next(s for s in r["stages"] if s["name"] == "dof")
            rows.append((d["fixed_ms"], d["notes"]["per_pixel_reference"]["ms"]))
        fx, pp = median_run(rows, lambda x: x[1] / x[0])
        print(f"| {scene} | {fx:.1f} | {pp:.1f} | {pp / fx:.2f} |")


def cycles_line(igemu, runs):
    rs = [json.loads(run([igemu, "cycles", "--json"]))["sim"] for _ in range(runs)]
    s = median_run(rs, lambda s: s["cycles_per_s"])
    print(
        f"Cycle simulator, default scene: {s['cycles_per_s'] / 1e6:.0f} M simulated cycles/s "
        f"({s['wall_ms']:.2f} ms; median of {runs})."
    )


def sweep_line(igemu, tmp):
    times = []
    for extra in ([], ["--no-reuse"]):
        out = os.path.join(tmp, "rows.jsonl")
        if os.path.exists(out):
            os.remove(out)
        t = time.monotonic()
        run([igemu, "sweep", "--grid", "examples/grid.toml", "--out", out, *extra])
        times.append(time.monotonic() - t)
    print(
        f"Sweep of examples/grid.toml (48 configurations, serial): {times[0]:.1f} s with stage "
        f"reuse, {times[1]:.1f} s with `--no-reuse`: reuse is {times[1] / times[0]:.1f}x faster."
    )


def dither_lines():
    p = subprocess.run(
        ["cargo", "bench", "--bench", "dither"], capture_output=True, text=True
    )
    if p.returncode != 0:
        sys.exit(f"cargo bench --bench dither: exit {p.returncode}\n{p.stderr}")
    lines = p.stdout.splitlines()
    # Criterion's estimates (the middle of `time: [low mid high]`) of the copy and LUT + Bayer.
    est = {}
    for i, l in enumerate(lines):
        if "time:" in l:
            name = l.split("time:")[0].strip() or lines[i - 1].strip()
            mid = l.split("[")[1].split()[2:4]
            est[name] = float(mid[0]) * {"ns": 1e-3, "µs": 1.0, "ms": 1e3}[mid[1]]
    if "dither/copy/u32" in est and "dither/lut+bayer8" in est:
        c, b = est["dither/copy/u32"], est["dither/lut+bayer8"]
        print(
            f"Criterion estimates: `dither/copy/u32` {c:.1f} us, `dither/lut+bayer8` {b:.1f} us: "
            f"LUT + Bayer 8x8 at {c / b:.3f} of the copy's throughput."
        )
        print()
    start = next(i for i, l in enumerate(lines) if l.startswith("dither ratios"))
    print("```")
    for l in lines[start:]:
        if l.strip():
            print(l)
    print("```")


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--igemu", default="target/release/igemu")
    ap.add_argument("--runs", type=int, default=3)
    ap.add_argument("--no-bench", action="store_true")
    a = ap.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        print("### Fixed model against its float reference\n")
        pipeline_table(a.igemu, a.runs, tmp)
        print("\n### Layered depth of field against the per-pixel scatter\n")
        dof_table(a.igemu, a.runs, tmp)
        print("\n### Cycle simulator and sweep reuse\n")
        cycles_line(a.igemu, a.runs)
        print()
        sweep_line(a.igemu, tmp)
        if not a.no_bench:
            print("\n### Gamma LUT + ordered dither against a copy\n")
            dither_lines()


if __name__ == "__main__":
    main()
