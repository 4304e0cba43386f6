#!/usr/bin/env python3
"""Plots of one `tachi run` (usage: plot_run.py [--after-sigusr1] OUT_DIR).

The launcher starts it with the run, with --after-sigusr1: it imports matplotlib (~1 s) while the run
goes and draws once the launcher, having written summary.json, sends it SIGUSR1.

latency.png: left, each stage's delay from the capture of the depth frame to that stage's output, p50
and p99 as the stage itself measured it (summary.json `<stage>_p50_ms`, `<stage>_p99_ms`: the same figures,
printed to stdout as `latency.png: <stage> p50 X ms p99 Y ms`); right, the end-to-end histogram: capture ->
the simulator's publication of the cloth state reflecting it, per depth frame (summary.json `latency_ms`).
The hand samples' arrival at the launcher (trace/*.csv) is no stage of the pipeline (it includes the
launcher's own scheduling) and is not drawn as one.
trajectory.png: raw hand (mapped onto the cloth the way the filter's default mirror mapping does),
smoothed hand (the filter's strokes) and the simulator's cut line, over the cloth's outline.
"""
import csv
import json
import os
import signal
import sys

if "--after-sigusr1" in sys.argv[1:]:
    # Held, not fatal, from here on (the launcher also starts it with SIGUSR1 blocked).
    signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGUSR1})

import matplotlib  # noqa: E402

matplotlib.use("Agg")  # no display needed
import matplotlib.pyplot as plt  # noqa: E402


def read_csv(path):
    if not os.path.exists(path):
        return []
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def main(out_dir):
    trace = os.path.join(out_dir, "trace")
    hands = read_csv(os.path.join(trace, "hands.csv"))
    strokes = read_csv(os.path.join(trace, "strokes.csv"))
    summary_path = os.path.join(out_dir, "summary.json")
    summary = json.load(open(summary_path)) if os.path.exists(summary_path) else {}
    config_path = os.path.join(out_dir, "config.json")
    config = json.load(open(config_path)) if os.path.exists(config_path) else {}

    stages = []
    for stage in ("sensor", "filter", "sim", "viewer"):
        p50, p99 = summary.get(f"{stage}_p50_ms"), summary.get(f"{stage}_p99_ms")
        if p50 is not None and p99 is not None:
            stages.append((stage, float(p50), float(p99)))
            print(f"latency.png: {stage} p50 {float(p50):.1f} ms p99 {float(p99):.1f} ms")
    fig, (ax_stages, ax) = plt.subplots(1, 2, figsize=(12, 5))
    if stages:
        xs = range(len(stages))
        ax_stages.bar([x - 0.2 for x in xs], [p50 for _, p50, _ in stages], width=0.4, label="p50")
        ax_stages.bar([x + 0.2 for x in xs], [p99 for _, _, p99 in stages], width=0.4, label="p99")
        ax_stages.set_xticks(list(xs))
        ax_stages.set_xticklabels([name for name, _, _ in stages])
        ax_stages.legend(fontsize=8)
    ax_stages.set_ylabel("capture -> the stage's output (ms)")
    ax_stages.set_title("per stage (summary.json <stage>_p50_ms / _p99_ms)")
    e2e = sorted(summary.get("latency_ms") or [])
    if e2e:
        p50 = e2e[len(e2e) // 2]
        p99 = e2e[min(len(e2e) - 1, int(0.99 * len(e2e)))]
        ax.hist(e2e, bins=40, alpha=0.6, label=f"capture -> cloth state published: n {len(e2e)}, p50 {p50:.2f} ms, p99 {p99:.2f} ms")
        ax.legend(fontsize=8)
    ax.set_xlabel("delay since the depth frame reached tachi-sensor (ms)")
    ax.set_ylabel("depth frames")
    ax.set_title("end to end (the simulator's last 1024 frames)")
    fig.suptitle("tachi run: latency")
    fig.tight_layout()
    fig.savefig(os.path.join(out_dir, "latency.png"), dpi=100)
    plt.close(fig)

    # The cloth: centred at the origin, x right, y up; (u, v) = (column, row) from the top-left corner.
    sim_options = config.get("sim", {})
    size = float(sim_options.get("size-m", 1.0))
    columns = int(summary.get("columns", config.get("grid", 64)))
    rows = int(summary.get("rows", columns))
    fig, ax = plt.subplots(figsize=(6, 6))
    ax.plot([-size / 2, size / 2, size / 2, -size / 2, -size / 2], [size / 2, size / 2, -size / 2, -size / 2, size / 2],
            color="0.5", label="cloth")
    raw = [(-float(r["x"]), -float(r["y"])) for r in hands if r["tracked"] == "1"]  # mirror mapping (docs/filter.md)
    if raw:
        ax.plot(*zip(*raw), ".", markersize=2, color="tab:orange", label="raw hand (mirrored)")
    smooth = [(float(r["x"]), float(r["y"])) for r in strokes if r["tracked"] == "1"]
    if smooth:
        ax.plot(*zip(*smooth), "-", linewidth=1, color="tab:blue", label="smoothed hand")
    cutting = [(float(r["x"]), float(r["y"])) for r in strokes if r["tracked"] == "1" and r["gate"] == "1"]
    if cutting:
        ax.plot(*zip(*cutting), ".", markersize=3, color="tab:red", label="while cutting")
    line = summary.get("cut_line") or []
    if line and columns > 1 and rows > 1:
        xs = [u * size / (columns - 1) - size / 2 for u, _ in line]
        ys = [size / 2 - v * size / (rows - 1) for _, v in line]
        ax.plot(xs, ys, "x", markersize=4, color="k", label="cut line (grid cells)")
    ax.set_aspect("equal")
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    ax.set_title("tachi run: hand and cut over the cloth")
    ax.legend(fontsize=8, loc="lower left")
    fig.tight_layout()
    fig.savefig(os.path.join(out_dir, "trajectory.png"), dpi=100)
    plt.close(fig)


if __name__ == "__main__":
    args = sys.argv[1:]
    after_signal = args[:1] == ["--after-sigusr1"]
    if after_signal:
        args = args[1:]
    if len(args) != 1:
        sys.exit("usage: plot_run.py [--after-sigusr1] OUT_DIR")
    if after_signal:
        signal.sigwait({signal.SIGUSR1})
    main(args[0])
