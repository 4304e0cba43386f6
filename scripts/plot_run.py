#!/usr/bin/env python3
"""Plots of one `tachi run` (called by the launcher after the run; usage: plot_run.py OUT_DIR).

latency.png: histogram per stage and end to end. Hand samples and strokes: capture of the depth frame
-> the sample's arrival at the launcher (OUT_DIR/trace/*.csv). End to end: capture -> the simulator's
publication of the cloth state reflecting it, per depth frame, as the simulator measured it
(summary.json `latency_ms`; exact on one host). The viewer's capture -> rendered image figures come from
its heartbeat (summary.json `viewer_p50_ms`, `viewer_p99_ms`): drawn as lines.
trajectory.png: raw hand (mapped onto the cloth the way the filter's default mirror mapping does),
smoothed hand (the filter's strokes) and the simulator's cut line, over the cloth's outline.
"""
import csv
import json
import os
import sys

import matplotlib

matplotlib.use("Agg")  # no display needed
import matplotlib.pyplot as plt  # noqa: E402


def read_csv(path):
    if not os.path.exists(path):
        return []
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def delays_ms(rows, start, end):
    out = []
    for r in rows:
        a, b = int(r[start]), int(r[end])
        if a > 0 and b >= a:
            out.append((b - a) * 1e-6)
    return out


def main(out_dir):
    trace = os.path.join(out_dir, "trace")
    hands = read_csv(os.path.join(trace, "hands.csv"))
    strokes = read_csv(os.path.join(trace, "strokes.csv"))
    summary_path = os.path.join(out_dir, "summary.json")
    summary = json.load(open(summary_path)) if os.path.exists(summary_path) else {}
    config_path = os.path.join(out_dir, "config.json")
    config = json.load(open(config_path)) if os.path.exists(config_path) else {}

    series = [
        ("sensor -> launcher (raw hand)", delays_ms(hands, "acquired_ns", "received_ns")),
        ("filter -> launcher (stroke)", delays_ms(strokes, "acquired_ns", "received_ns")),
        ("end to end: capture -> cloth state published", list(summary.get("latency_ms") or [])),
    ]
    fig, ax = plt.subplots(figsize=(8, 5))
    for label, values in series:
        if values:
            values.sort()
            p50 = values[len(values) // 2]
            p99 = values[min(len(values) - 1, int(0.99 * len(values)))]
            ax.hist(values, bins=40, alpha=0.5, label=f"{label}: n {len(values)}, p50 {p50:.2f} ms, p99 {p99:.2f} ms")
    for key, style in (("viewer_p50_ms", "--"), ("viewer_p99_ms", ":")):
        if summary.get(key) is not None:
            ax.axvline(summary[key], color="k", linestyle=style, label=f"viewer capture -> image {key[7:10]}: {summary[key]:.1f} ms")
    ax.set_xlabel("delay since the depth frame reached tachi-sensor (ms)")
    ax.set_ylabel("samples")
    ax.set_title("tachi run: latency per stage")
    ax.legend(fontsize=8)
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
    if len(sys.argv) != 2:
        sys.exit("usage: plot_run.py OUT_DIR")
    main(sys.argv[1])
