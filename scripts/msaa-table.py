#!/usr/bin/env python3
"""Markdown tables from scripts/bench-msaa.sh's JSON: median GPU ms per pass over the frames
after the first two, memory of the G-buffer-related resources, and ratios of the compressed
methods (stencil and sample-claim) to the per-sample and Z-prepass baselines.
Usage: msaa-table.py DIR"""
import json, statistics, sys, pathlib

GBUFFER = {"albedo", "normal", "depth", "gbuffer", "head_samples", "sample_claim", "ids"}

def load(path):
    d = json.loads(path.read_text())
    frames = d["frames"][2:] or d["frames"]
    passes = {}
    for f in frames:
        for t in f["gpu_ms"]:
            passes.setdefault(t["name"], []).append(t["ms"])
    ms = {k: statistics.median(v) for k, v in passes.items()}
    total = statistics.median([f["gpu_total_ms"] for f in frames])
    mem = {r["name"]: r["bytes"] for r in d.get("resources", []) if r["name"] in GBUFFER}
    g = frames[-1].get("gbuffer", [{}])
    ref = d.get("reference") or {}
    return ms, total, mem, (g[0] if g else {}), ref

def mib(b):
    return b / 2**20

root = pathlib.Path(sys.argv[1])
rows = []
for p in sorted(root.glob("*.json")):
    scene, method, msaa, lights = p.stem.split("-")
    rows.append((scene, int(lights), int(msaa[:-1]), method, *load(p)))
print("| scene | lights | MSAA | method | frame ms | geometry ms | lighting ms | G-buffer+depth MiB | pool used / blocks | overflow samples | mean FLIP | PSNR dB |")
print("|---|---|---|---|---|---|---|---|---|---|---|---|")
for scene, lights, msaa, method, ms, total, mem, g, ref in sorted(rows):
    geometry = sum(v for k, v in ms.items() if k.startswith(("draw_", "depth_", "gbuffer")))
    lighting = ms.get("lighting", 0)
    pool = f"{g.get('pool_used', '-')} / {g.get('pool_blocks', '-')}" if g else "-"
    print(f"| {scene} | {lights} | {msaa}x | {method} | {total:.3f} | {geometry:.3f} | {ms.get('lighting', 0):.3f} | "
          f"{mib(sum(mem.values())):.1f} | {pool} | {g.get('overflow_samples', '-') if g else '-'} | "
          f"{ref.get('mean_flip', float('nan')):.4f} | {ref.get('psnr_db') or float('nan'):.2f} |")
print()
# One row per compressed method: with stencil (msaa_compressed) and with sample claims
# (msaa_compressed_claim, a depth without stencil).
COMPRESSED = {"msaa_compressed": "stencil", "msaa_compressed_claim": "claim"}
print("| scene | lights | MSAA | compressed | memory / per-sample | lighting / per-sample | frame / per-sample | frame / Z-prepass | FLIP - per-sample |")
print("|---|---|---|---|---|---|---|---|---|")
index = {(s, l, m, meth): (ms, t, mem, ref) for s, l, m, meth, ms, t, mem, _, ref in rows}
for (s, l, m, meth), (ms, t, mem, ref) in sorted(index.items()):
    if meth not in COMPRESSED:
        continue
    ps, zp = index.get((s, l, m, "msaa_per_sample")), index.get((s, l, m, "msaa_zprepass"))
    if not ps or not zp:
        continue
    print(f"| {s} | {l} | {m}x | {COMPRESSED[meth]} | {sum(mem.values()) / max(1, sum(ps[2].values())):.2f} | "
          f"{ms.get('lighting', 0) / max(1e-9, ps[0].get('lighting', 0)):.2f} | {t / ps[1]:.2f} | {t / zp[1]:.2f} | "
          f"{ref.get('mean_flip', float('nan')) - ps[3].get('mean_flip', float('nan')):+.4f} |")
