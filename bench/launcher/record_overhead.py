#!/usr/bin/env python3
"""What `tachi run --record` costs the pipeline it records: the same 128 x 128 run with and
without the recorder, alternately (so both see the same machine load), its end-to-end p50 (depth
frame capture -> the cloth state reflecting it, the simulator's `latency_ms` over the run's frames),
and whether the recording dropped anything: DDS-reported lost samples (SAMPLE_LOST on the
recorder's keep-all readers), and the recorded counts against what the nodes published: one raw hand
sample and one stroke sample per depth frame, and every cut event the simulator counted. Also the CPU
seconds of the whole run (launcher and nodes, user + system): what recording costs the machine.

Usage: record_overhead.py BIN_DIR RECORDING [PAIRS [GRID]]   (domain 149; default 5 pairs, grid 128)
"""
import json
import os
import resource
import statistics
import subprocess
import sys
import tempfile


def pct(values, p):
    values = sorted(values)
    return values[min(len(values) - 1, max(0, int(round(p / 100.0 * len(values))) - 1))]


def depth_frames(recording):
    with open(os.path.join(recording, "INDEX.txt")) as f:
        return sum(1 for line in f if line.startswith("d-"))


def one_run(bin_dir, recording, grid, record):
    with tempfile.TemporaryDirectory(prefix="tachi-record-bench-") as out:
        cmd = [os.path.join(bin_dir, "tachi"), "run", "--recording", recording, "--grid", str(grid), "--domain", "149",
               "--out", out, "--headless", "--settle", "1"] + (["--record"] if record else [])
        before = resource.getrusage(resource.RUSAGE_CHILDREN)
        done = subprocess.run(cmd, capture_output=True, text=True, timeout=300)
        after = resource.getrusage(resource.RUSAGE_CHILDREN)
        if done.returncode != 0:
            sys.exit(f"run failed ({done.returncode}): {' '.join(cmd)}\n{done.stderr[-2000:]}")
        summary = json.load(open(os.path.join(out, "summary.json")))
        # CPU seconds of the launcher and every node it waited for (user + system).
        summary["cpu_s"] = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
        return summary


def main():
    if len(sys.argv) < 3:
        sys.exit(__doc__)
    bin_dir, recording = sys.argv[1], sys.argv[2]
    pairs = int(sys.argv[3]) if len(sys.argv) > 3 else 5
    grid = int(sys.argv[4]) if len(sys.argv) > 4 else 128
    frames = depth_frames(recording)
    print(f"recording {recording} ({frames} depth frames), grid {grid}, {pairs} pairs run alternately")
    print("pair  e2e_p50 without  e2e_p50 with  difference  cpu_s without  with  recorded: hand/raw stroke cut state  lost  bytes")
    without, with_, diffs, drops, cpu = [], [], [], 0, []
    for pair in range(pairs):
        a = one_run(bin_dir, recording, grid, False)
        b = one_run(bin_dir, recording, grid, True)
        pa, pb = pct(a["latency_ms"], 50), pct(b["latency_ms"], 50)
        without.append(pa)
        with_.append(pb)
        diffs.append(pb - pa)
        cpu.append(b["cpu_s"] - a["cpu_s"])
        r = b["recording"]
        m = r["messages"]
        ok = (m["tachi/hand/raw"] == frames and m["tachi/hand/stroke"] == frames and m["tachi/cloth/cut"] == b["cuts"]
              and r["lost"] == 0)
        drops += 0 if ok else 1
        print(f"{pair:4d}  {pa:15.2f}  {pb:12.2f}  {pb - pa:10.2f}  {a['cpu_s']:13.2f}  {b['cpu_s']:4.2f}  {m['tachi/hand/raw']:17d} {m['tachi/hand/stroke']:6d} "
              f"{m['tachi/cloth/cut']:3d} {m['tachi/cloth/state']:5d}  {r['lost']:4d}  {r['bytes']}{'' if ok else '  DROPPED'}")
    print(f"median e2e p50: without {statistics.median(without):.2f} ms, with --record {statistics.median(with_):.2f} ms; "
          f"median of the pairs' differences {statistics.median(diffs):+.2f} ms (target <= +0.5 ms); "
          f"runs that dropped a sample: {drops} of {pairs}; median extra CPU of a recorded run {statistics.median(cpu):+.2f} s")


if __name__ == "__main__":
    main()
