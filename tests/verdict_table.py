#!/usr/bin/env python3
"""Every shared input through every method that takes it, with the verdict's figures.

    python3 tests/verdict_table.py BIN [OUT.md] [--only SUBSTRING] [--timeout S]

Runs BIN (the release CLI) on ../shared/data/meshes/*.obj (st at eps 2e-3 and 4e-4, st-support) and
../shared/data/bsplines/*.json, hard/*.json (st, st-support, sq), writes only report.json and the
schedule, and prints one Markdown row per run: exit code, panels with crossing arcs, other panels
without an exact surface, support elements that fold, folded faces, distance against its bound,
coverage (SQ), and what was missed. Figures are read from report.json as written.
"""
import glob
import json
import os
import subprocess
import sys
import tempfile
import time

HERE = os.path.dirname(os.path.abspath(__file__))
SHARED = os.path.join(HERE, "..", "..", "shared", "data")


def runs():
    for mesh in sorted(glob.glob(os.path.join(SHARED, "meshes", "*.obj"))):
        name = os.path.basename(mesh)
        yield name, "st ε 2e-3", ["st", mesh, "--epsilon", "0.002"]
        yield name, "st ε 4e-4", ["st", mesh, "--epsilon", "0.0004"]
        yield name, "st-support", ["st-support", mesh]
    splines = sorted(glob.glob(os.path.join(SHARED, "bsplines", "*.json")))
    splines += sorted(glob.glob(os.path.join(SHARED, "bsplines", "hard", "*.json")))
    for spline in splines:
        name = os.path.relpath(spline, os.path.join(SHARED, "bsplines"))
        if name == "reference_samples.json":
            continue
        yield name, "st", ["st", spline]
        yield name, "st-support", ["st-support", spline]
        yield name, "sq", ["sq", spline]


def guarantee(report, name):
    for g in report.get("guarantees", []):
        if g["name"] == name:
            return g
    return None


def row(binary, input_name, label, args, timeout):
    with tempfile.TemporaryDirectory(prefix="sf-verdict-") as out:
        return run_in(binary, input_name, label, args, timeout, out)


def run_in(binary, input_name, label, args, timeout, out):
    t0 = time.time()
    try:
        p = subprocess.run([binary, *args, "-q", "--formats", "schedule", "--out", out], capture_output=True, text=True, timeout=timeout)
        code = str(p.returncode)
        err = p.stderr.strip().splitlines()[-1] if p.stderr.strip() else ""
    except subprocess.TimeoutExpired:
        code, err = "timeout", ""
    secs = time.time() - t0
    path = os.path.join(out, "report.json")
    if code in ("1", "2", "timeout") or not os.path.exists(path):
        return f"| {input_name} | {label} | {code} | | | | | | | {secs:.0f} s | {err[:120]} |"
    r = json.load(open(path))
    refused = (r.get("exact_surfaces") or {}).get("refused", [])
    crossing = sum(1 for x in refused if x["kind"] == "panel" and "cross" in x["reason"])
    other = sum(1 for x in refused if x["kind"] == "panel" and "cross" not in x["reason"])
    support = sum(1 for x in refused if x["kind"] != "panel")
    folds = guarantee(r, "folded_faces")
    dist = guarantee(r, "max_distance_to_reference")
    metrics = r.get("metrics") or {}
    if dist:
        d = f"{dist['measured']:.2e} / {dist['limit']:.1e}"
    else:
        d = f"{metrics.get('max_distance_to_reference', float('nan')):.2e} / –"
    cov = guarantee(r, "coverage")
    if cov:
        c = f"{100 * cov['measured']:.1f} %"
    else:
        q = (r.get("sq") or {}).get("quad_mesh") or {}
        c = f"{100 * q['coverage']:.1f} % (reported)" if "coverage" in q else ""
    missed = ", ".join(g["name"] for g in r.get("guarantees", []) if not g["holds"])
    f = "" if folds is None else str(int(folds["measured"]))
    return f"| {input_name} | {label} | {code} | {crossing} | {other} | {support} | {f} | {d} | {c} | {secs:.0f} s | {missed} |"


def main():
    args = sys.argv[1:]
    only, timeout = None, 900
    if "--only" in args:
        i = args.index("--only")
        only = args[i + 1]
        del args[i:i + 2]
    if "--timeout" in args:
        i = args.index("--timeout")
        timeout = float(args[i + 1])
        del args[i:i + 2]
    binary = args[0]
    out = open(args[1], "w") if len(args) > 1 else None
    head = "| input | method | exit | crossing arcs | other refused panels | support folds | folded faces | distance / bound (of the diagonal) | coverage | time | missed |\n|---|---|---|---|---|---|---|---|---|---|---|"
    print(head, flush=True)
    if out:
        print(head, file=out, flush=True)
    for input_name, label, a in runs():
        if only and only not in f"{input_name} {label}":
            continue
        line = row(binary, input_name, label, a, timeout)
        print(line, flush=True)
        if out:
            print(line, file=out, flush=True)


if __name__ == "__main__":
    main()
