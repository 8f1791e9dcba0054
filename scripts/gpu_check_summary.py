#!/usr/bin/env python3
"""summary.md for scripts/gpu-check: the outputs of one run in a few tables.

Usage: gpu_check_summary.py OUT_DIR  (prints Markdown)
"""
import json
import pathlib
import sys

out = pathlib.Path(sys.argv[1])


def text(name):
    p = out / f"{name}.txt"
    return p.read_text(errors="replace") if p.exists() else ""


def hash_lines(name):
    """{case and texture: hash} of a product-hashes run; pass lists kept apart."""
    textures, passes = {}, {}
    for line in text(f"hashes-{name}").splitlines():
        if " | passes " in line:
            passes[line.split(" | ")[0]] = line
        elif " | " in line:
            key, _, rest = line.rpartition(" ")
            textures[key] = rest
    return textures, passes


print("# gpu-check\n")
print("## The machine\n")
for name in ("nvidia-smi", "devices"):
    body = text(name).strip()
    if body:
        print(f"```\n{body}\n```\n")

print("## product-hashes\n")
print("| run | against | texture lines | equal | differing | pass lists differing |")
print("| --- | --- | ---: | ---: | ---: | ---: |")
base_t, base_p = hash_lines("cpu-device-cpu-profile")
differing = {}
for run in ("gpu-device-cpu-profile", "gpu-device-gpu-profile"):
    t, p = hash_lines(run)
    keys = set(t) | set(base_t)
    differing[run] = sorted(k for k in keys if t.get(k) != base_t.get(k))
    passes = sum(1 for k in set(p) | set(base_p) if p.get(k) != base_p.get(k))
    print(f"| {run} | cpu-device-cpu-profile | {len(t)} | {len(keys) - len(differing[run])} | "
          f"{len(differing[run])} | {passes} |")
print()
for run, keys in differing.items():
    if keys:
        print(f"{run}, the first of its differing lines:\n")
        print("```\n" + "\n".join(keys[:15]) + "\n```\n")


def runs_of(name):
    """The non-aggregate runs of a bench's JSON output."""
    p = out / f"{name}.json"
    if not p.exists():
        return []
    try:
        data = json.loads(p.read_text())
    except json.JSONDecodeError:
        return []
    return [b for b in data.get("benchmarks", []) if b.get("run_type") != "aggregate"]


def bench(name):
    """{benchmark (and its label): ms}."""
    scale = {"ns": 1e-6, "us": 1e-3, "ms": 1.0, "s": 1e3}
    return {" ".join(filter(None, (b["name"], b.get("label")))):
            b["real_time"] * scale[b.get("time_unit", "ns")] for b in runs_of(name)}


for family in ("raster", "pixels", "filter"):
    runs = {r: bench(f"{family}-{r}") for r in ("gpu-gpu", "gpu-cpu", "cpu-cpu")}
    names = sorted(set().union(*runs.values()))
    if not names:
        continue
    print(f"## {family} bench, ms (device, kernel profile)\n")
    print("| benchmark | GPU, gpu profile | GPU, cpu profile | CPU device, cpu profile | "
          "cpu-device / gpu-gpu |")
    print("| --- | ---: | ---: | ---: | ---: |")
    for n in names:
        v = [runs[r].get(n) for r in ("gpu-gpu", "gpu-cpu", "cpu-cpu")]
        cells = [f"{x:.3f}" if x is not None else "—" for x in v]
        ratio = f"{v[2] / v[0]:.1f}x" if v[0] and v[2] else "—"
        print(f"| {n} | {' | '.join(cells)} | {ratio} |")
    print()

# The passes the goals name, from the pixels bench's counters (ms).
wanted = ("gbuffer.resolve_ms", "csm.basis_ms", "csm.mips_ms", "visibility.csm_ms",
          "gbuffer_ms", "shadow_map_ms", "visibility_ms")
rows = []
for run in ("gpu-gpu", "gpu-cpu", "cpu-cpu"):
    for b in runs_of(f"pixels-{run}"):
        cells = [f"{k[:-3]} {b[k]:.3f}" for k in wanted if k in b]
        if cells:
            rows.append(f"| {run} | {b['name']} {b.get('label', '')} | {', '.join(cells)} |")
if rows:
    print("## pixels bench, passes (ms)\n")
    print("| run | benchmark | passes |")
    print("| --- | --- | --- |")
    print("\n".join(rows) + "\n")

print("## The suite on the GPU\n")
suite = text("suite-gpu").strip().splitlines()
print("```\n" + "\n".join(suite[-40:]) + "\n```\n")
print("## Steps\n")
print("```\n" + (out / "steps.log").read_text() + "```")
