#!/usr/bin/env python3
"""End-to-end latency of the live pipeline: depth frame capture -> the published cloth state that
reflects it, at two grid sizes, on one host (docs/benchmarks.md "End-to-end latency").

Each run is `tachi run` on a bundled recording (all nodes, loopback, headless). The capture stamp is
taken when the depth frame reaches tachi-sensor, after the recording's pacing sleep, so pacing is
excluded; the cloth state carries that stamp and the simulator's publication time (same host, same
clock). The simulator measures each depth frame's delay to the first state reflecting it and exports
them (summary.json `latency_ms`). Baseline in the same run: capture -> the raw hand sample's arrival at the launcher
(OUT/trace/hands.csv), the floor any DDS pipeline stage pays; the ratio says what filtering, mapping,
gating, cutting and publishing the cloth add on top of one hop.

With --both-modes first among the flags, each grid is run as processes (one a node) and
`--in-process` (tachi-pipeline: the nodes as threads of one process), the runs of the two interleaved
so that the machine's drift falls on both: one table, a mode column.

Usage: e2e_latency.py BIN_DIR RECORDING [RUNS [--both-modes] [TACHI_RUN_FLAGS...]]
       (domain 149; RUNS fresh runs per grid (and mode), default 3; e.g. --set sim.cut-mode=grid)
"""
import csv
import json
import os
import statistics
import subprocess
import sys
import tempfile


def delays(path, start, end):
    with open(path, newline="") as f:
        return [(int(r[end]) - int(r[start])) * 1e-6 for r in csv.DictReader(f) if int(r[start]) > 0]


def pct(values, p):
    values = sorted(values)
    return values[min(len(values) - 1, max(0, int(round(p / 100.0 * len(values))) - 1))]


def main():
    if len(sys.argv) < 3:
        sys.exit(__doc__)
    bin_dir, recording = sys.argv[1], sys.argv[2]
    runs = int(sys.argv[3]) if len(sys.argv) > 3 else 3
    extra = sys.argv[4:]
    modes = {"processes": []}
    if extra[:1] == ["--both-modes"]:
        extra = extra[1:]
        modes["in-process"] = ["--in-process"]
    print(f"recording {recording}, {runs} fresh runs per grid and mode, flags {' '.join(extra) or '(none)'}; "
          "per run: p50/p99 over its depth frames (ms)")
    print("grid  mode        run  frames  e2e_p50  e2e_p99  hop_p50  hop_p99  e2e_p50/hop_p50")
    for grid in (64, 128):
        rows = {mode: [] for mode in modes}
        for run, mode in [(run, mode) for run in range(runs) for mode in modes]:
            with tempfile.TemporaryDirectory(prefix="tachi-e2e-bench-") as out:
                cmd = [os.path.join(bin_dir, "tachi"), "run", "--recording", recording, "--grid", str(grid), "--domain", "149",
                       "--out", out, "--headless", "--settle", "1"] + modes[mode] + extra
                done = subprocess.run(cmd, capture_output=True, text=True, timeout=300)
                if done.returncode != 0:
                    sys.exit(f"run failed ({done.returncode}): {' '.join(cmd)}\n{done.stderr[-2000:]}")
                hop = delays(os.path.join(out, "trace", "hands.csv"), "acquired_ns", "received_ns")
                summary = json.load(open(os.path.join(out, "summary.json")))
                e2e = summary["latency_ms"]
            if not e2e or not hop:
                # A run whose cloth never reflected a frame (or whose trace is empty) has no latency to
                # quote: say so instead of a figure (seen with Cyclone's default timing at 10% loss).
                print(f"{grid:4d}  {mode:10s}  {run:3d}  {len(e2e):6d}  no e2e samples ({len(hop)} hops); hand_samples "
                      f"{summary.get('hand_samples')}, cuts {summary.get('cuts')}")
                continue
            row = (pct(e2e, 50), pct(e2e, 99), pct(hop, 50), pct(hop, 99))
            rows[mode].append(row)
            print(f"{grid:4d}  {mode:10s}  {run:3d}  {len(e2e):6d}  {row[0]:7.2f}  {row[1]:7.2f}  {row[2]:7.2f}  {row[3]:7.2f}  "
                  f"{row[0] / row[2]:6.2f}   (heartbeat: sim p50 {summary['sim_p50_ms']:.2f} p99 {summary['sim_p99_ms']:.2f})")
        for mode in modes:
            if not rows[mode]:
                print(f"{grid:4d}  {mode:10s}  no run had e2e samples")
                continue
            med = [statistics.median(r[i] for r in rows[mode]) for i in range(4)]
            print(f"{grid:4d}  {mode:10s}  median of runs: e2e p50 {med[0]:.2f} ms, p99 {med[1]:.2f} ms; hop p50 {med[2]:.2f} ms, "
                  f"p99 {med[3]:.2f} ms; ratio {med[0] / med[2]:.2f}  (targets: p50 <= 5 ms, p99 <= 16 ms)")


if __name__ == "__main__":
    main()
