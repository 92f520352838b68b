#!/usr/bin/env python3
"""The cost curves of docs/speed.md: the fixed-only frame (`igemu render --no-reference
--json`) of the default scene over resolutions (same camera, lens and aspect) and over
tessellations (the objects' primitives), per stage, medians of --runs renders.

    cargo build --release && python3 examples/cost_curves.py --runs 5

Each render is one process (a one-shot frame: its planes are allocated afresh, page faults
included; `cargo bench --bench frame` measures the pooled frames of a run).
"""
import argparse
import json
import os
import re
import statistics
import subprocess
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
SCENE = os.path.join(ROOT, "src", "scene", "default.toml")
STAGES = ["input", "setup", "raster", "visibility", "accumulate", "dof", "gamma"]


def render(igemu, text, tmp, runs):
    path = os.path.join(tmp, "scene.toml")
    with open(path, "w") as f:
        f.write(text)
    per = {s: [] for s in STAGES}
    work = {}
    for _ in range(runs):
        out = subprocess.run(
            [igemu, "render", path, "--no-reference", "--json", "-o", os.path.join(tmp, "o.png")],
            check=True, capture_output=True, text=True).stdout
        r = json.loads(out)
        for s in r["stages"]:
            if s["name"] in per:
                per[s["name"]].append(s["fixed_ms"])
            work[s["name"]] = s["work"]
    return {s: statistics.median(v) for s, v in per.items() if v}, work


def sized(text, w, h):
    text = re.sub(r"(?m)^width = \d+", f"width = {w}", text, count=1)
    return re.sub(r"(?m)^height = \d+", f"height = {h}", text, count=1)


def tessellated(text, scale):
    return re.sub(r"(?m)^tessellation = (\d+)",
                  lambda m: f"tessellation = {min(1024, int(m.group(1)) * scale // 4)}", text)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--runs", type=int, default=5)
    ap.add_argument("--igemu", default=os.path.join(ROOT, "target", "release", "igemu"))
    a = ap.parse_args()
    base = open(SCENE).read()
    with tempfile.TemporaryDirectory() as tmp:
        print("Resolution (default scene, linear12, thin lens; ms per stage, fixed only):\n")
        print("| screen | pixels | " + " | ".join(STAGES) + " | total | total ns/pixel | dof ns/pixel |")
        print("|---" * (len(STAGES) + 5) + "|")
        for w, h in [(320, 240), (640, 480), (1280, 960), (2560, 1920)]:
            ms, _ = render(a.igemu, sized(base, w, h), tmp, a.runs)
            px = w * h
            total = sum(ms.values())
            cells = " | ".join(f"{ms.get(s, 0):.2f}" for s in STAGES)
            print(f"| {w}x{h} | {px} | {cells} | {total:.2f} | {total * 1e6 / px:.1f} | "
                  f"{ms.get('dof', 0) * 1e6 / px:.1f} |")
        print("\nPrimitives (default scene at 640x480, tessellation scaled; ms per stage):\n")
        print("| tessellation x | primitives | samples | " + " | ".join(STAGES) + " | total |")
        print("|---" * (len(STAGES) + 4) + "|")
        for scale in [2, 4, 8, 16]:
            ms, work = render(a.igemu, tessellated(base, scale), tmp, a.runs)
            prims = work.get("input", {}).get("primitives", 0)
            samples = work.get("raster", {}).get("samples", 0)
            cells = " | ".join(f"{ms.get(s, 0):.2f}" for s in STAGES)
            print(f"| {scale / 4:g} | {prims} | {samples} | {cells} | {sum(ms.values()):.2f} |")


if __name__ == "__main__":
    main()
