#!/usr/bin/env python3
"""Runs `squeeze mesh` over surfaces and targets and checks issue 16's criteria on each report.

Usage: scripts/mesh_matrix.py [--squeeze build/squeeze] [--targets 150,300,1000,default]
                              [--out DIR] [--markdown] [--mesh-args "--winding"] FILE...
Prints one row per (file, target): tets, volume ratio, deviation_out / deviation_in (percent of the
bounding-box diagonal), min dihedral, seconds, and pass/fail with the failed criteria named:
  exit 0; volume ratio in [0.9, 1.2] for closed inputs ([0.95, 1.1] at 1000 tets and above);
  deviation_out <= 1.5 %, deviation_in <= 0.5 %; min dihedral >= 5 degrees; as many tet-mesh
  components as connected input parts, each conforming (the report's tets.conforming); tets within
  +-35 % of the target unless the report's target_exceeded_because says why; at most 15 s.
"""
import argparse
import json
import os
import subprocess
import sys
import tempfile
import time


def check(r, target, seconds):
    fails = []
    closed = r["input"]["closed"]
    vr = r["volume_ratio"]
    t = target if target is not None else r["target_tets"]
    if closed:
        lo, hi = (0.95, 1.1) if t >= 1000 else (0.9, 1.2)
        if vr is None or not (lo <= vr <= hi):
            fails.append("volume")
    if r["deviation_out"] > 0.015:
        fails.append("dev_out")
    if r["deviation_in"] > 0.005:
        fails.append("dev_in")
    if r["tets"]["min_dihedral_deg"] < 5.0:
        fails.append("dihedral")
    if r["tets"]["components"] != r["input"]["connected_parts"]:
        fails.append("components")
    if not r["tets"].get("conforming", True):  # "one conforming mesh per connected input part"
        fails.append("conforming")
    n = r["tets"]["tets"]
    if not (0.65 * t <= n <= 1.35 * t) and not r["target_exceeded_because"]:
        fails.append("count")
    if seconds > 15:
        fails.append("time")
    return fails


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--squeeze", default="build/squeeze")
    ap.add_argument("--targets", default="150,300,1000,default")
    ap.add_argument("--out", default=None, help="keep reports and meshes here")
    ap.add_argument("--markdown", action="store_true")
    ap.add_argument("--mesh-args", default="", help="extra `squeeze mesh` arguments, e.g. \"--winding\"")
    ap.add_argument("files", nargs="+")
    a = ap.parse_args()
    out = a.out or tempfile.mkdtemp(prefix="mesh_matrix_")
    os.makedirs(out, exist_ok=True)
    rows, failed = [], 0
    header = "| input | target | tets | volume ratio | dev out % | dev in % | min dihedral | s | result |"
    print(header)
    print("|---|---|---|---|---|---|---|---|---|")
    for f in a.files:
        for ts in a.targets.split(","):
            target = None if ts == "default" else int(ts)
            stem = os.path.splitext(os.path.basename(f))[0] + "_" + ts
            rep = os.path.join(out, stem + ".json")
            cmd = [a.squeeze, "-q", "mesh", f, "-o", os.path.join(out, stem + ".mesh"), "--report", rep]
            if target is not None:
                cmd += ["--target-tets", str(target)]
            cmd += a.mesh_args.split()
            t0 = time.time()
            p = subprocess.run(cmd, capture_output=True, text=True)
            sec = time.time() - t0
            name = os.path.basename(f)
            if p.returncode != 0:
                failed += 1
                print(f"| {name} | {ts} | - | - | - | - | - | {sec:.1f} | FAIL (exit {p.returncode}: {p.stderr.strip()[:80]}) |")
                continue
            r = json.load(open(rep))
            fails = check(r, target, sec)
            failed += bool(fails)
            vr = r["volume_ratio"]
            n = r["tets"]["tets"]
            note = "" if not r["target_exceeded_because"] else " (over: see report)"
            print(f"| {name} | {ts} | {n}{note} | {'open' if vr is None else f'{vr:.3f}'} | "
                  f"{100 * r['deviation_out']:.2f} | {100 * r['deviation_in']:.2f} | "
                  f"{r['tets']['min_dihedral_deg']:.1f} | {sec:.1f} | {'pass' if not fails else 'FAIL ' + ','.join(fails)} |",
                  flush=True)
    print(f"\n{failed} failing row(s); reports in {out}")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
