#!/usr/bin/env python3
"""Paper 004's experiment: the (mesh, texture) pair chosen at several byte
budgets on the Olinda DEM + Landsat pair (fixtures/), optimum vs the paper's
greedy scan. Prints the Markdown table of docs/paper004.md.

Usage: python3 bench/paper004.py [COTA]   (COTA defaults to target/release/cota;
build it first with `cargo build --release --bin cota`)
"""
import json
import subprocess
import sys

COTA = sys.argv[1] if len(sys.argv) > 1 else "target/release/cota"
DEM, IMAGE = "fixtures/olinda_dem_utm25s.tif", "fixtures/L7_ETMs.tif"
BUDGETS = [15_000, 40_000, 80_000, 120_000, 200_000, 300_000, 400_000, 530_000]
WEIGHTS = [(1, 1), (10, 1), (100, 1), (1000, 1)]


def run(budget, alpha=1, beta=1):
    out = subprocess.run(
        [COTA, "pair", DEM, IMAGE, "--bands", "3,2,1", "--budget-bytes", str(budget),
         "--alpha", str(alpha), "--beta", str(beta), "--json"],
        check=True, capture_output=True, text=True).stdout
    return json.loads(out)


def pair(p):
    if p is None:
        return "none", "", ""
    mesh = f"{p['hierarchy']} {p['tolerance_m']:g} m, {p['triangles']} tri, {p['mesh_bytes']} B"
    tex = f"σ {p['texture_tolerance']:g}, {p['leaves']} leaves, {p['texture_bytes']} B"
    return mesh, tex, f"{p['d_mesh_m2']:.3g} + {p['d_texture']:.4g} = {p['distortion']:.4g}"


def main():
    print("| budget (B) | optimum mesh | optimum texture | optimum D(M) + D(T) = D"
          " | greedy mesh | greedy texture | greedy D | gap in D | choose (µs) |")
    print("|---|---|---|---|---|---|---|---|---|")
    sweep = []
    for b in BUDGETS:
        r = run(b)
        om, ot, od = pair(r["optimum"])
        gm, gt, gd = pair(r["greedy"])
        gap = r["greedy_gap"]
        if gap is None:
            gap = "—"
        elif r["optimum"]["distortion"] < 1e-6:  # an exact mesh: D(M) is rounding noise
            gap = f"{gap:.3g}"
        else:
            gap = f"{gap:.3g} (+{100 * r['greedy_gap_relative']:.0f} %)"
        t = r["timing"]
        sweep.append((t["sweep_budgets"], t["sweep_us"]))
        print(f"| {b} | {om} | {ot} | {od} | {gm} | {gt} | {gd.split(' = ')[-1]} | {gap}"
              f" | {t['choose_us']:.1f} |")
    n, us = max(sweep, key=lambda s: s[1])
    print(f"\nOptimum for every distinct budget ({n} of them), slowest of the runs: {us:.0f} µs.")
    print(f"Lists (meshes, textures): {len(r['meshes'])}, {len(r['textures'])};"
          f" building them {r['timing']['lists_ms']:.0f} ms.")

    print("\nWeighted, D = α·D(M) + β·D(T), budget 200000 B:\n")
    print("| α | β | optimum mesh | optimum texture | D(M) + D(T) | greedy gap in D |")
    print("|---|---|---|---|---|---|")
    for a, b in WEIGHTS:
        r = run(200_000, a, b)
        om, ot, od = pair(r["optimum"])
        gap = r["greedy_gap"]
        gap = "—" if gap is None else f"{gap:.3g} (+{100 * r['greedy_gap_relative']:.0f} %)"
        print(f"| {a} | {b} | {om} | {ot} | {od.split(' = ')[0]} | {gap} |")


main()
