#!/usr/bin/env python3
"""Soak: a recording looped through `tachi run` for MINUTES, watched from outside (docs/benchmarks.md
"Soak"). Every 10 s it samples each node's resident memory (VmRSS) and open file descriptors from
/proc; the latency is the launcher's trace (OUT/trace/strokes.csv: depth frame captured -> its
filtered stroke sample received by the launcher, the path every cut takes). At the end it sends the
run SIGINT, as a user's Ctrl-C, and reads summary.json for restarts.

Per minute: each node's median RSS, anonymous memory (RssAnon: its own heap, arenas and stacks; RSS adds
the shared libraries' resident pages, which come and go with the code run and the page cache) and
descriptors, the latency p50/p99. The verdict compares the last minute with the end of the warm-up, minute
max(1, MINUTES / 6) (10 for an hour): RSS, anonymous memory and descriptors within 2 %, latency p99 within
2x, no restart. Exit 0 when all hold, 1 if not. The
growth from minute 1 is printed too. Why a warm-up: a node's heap is flat after ~40 s (heaptrack on
tachi-filter: 6.8 MB from 40 s to 200 s), but its RSS still grows for minutes as the pages of
buffers allocated at the start (Cyclone's receive buffers, the writers' history caches) are touched
for the first time.

With TACHI_SOAK_KEEP=DIR the run's folder (summary.json, trace/, logs) is copied there.

Usage: soak.py BIN_DIR RECORDING MINUTES [TACHI_RUN_FLAGS...]   (domain 148)
       e.g. soak.py build/bin build/recordings/straight_cut 5 --grid 64
"""
import csv
import json
import os
import shutil
import signal
import statistics
import subprocess
import sys
import tempfile
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from e2e_latency import pct  # noqa: E402  (the same percentile as the latency benchmark)

SAMPLE_S = 10.0
DOMAIN = "148"


def children_of(pid):
    """PID -> command name of the launcher's direct children (the nodes)."""
    found = {}
    for entry in os.listdir("/proc"):
        if not entry.isdigit():
            continue
        try:
            with open(f"/proc/{entry}/stat") as f:
                stat = f.read()
            ppid = int(stat.rsplit(")", 1)[1].split()[1])
            if ppid == pid:
                with open(f"/proc/{entry}/comm") as f:
                    found[int(entry)] = f.read().strip()
        except (OSError, ValueError, IndexError):
            continue  # a process that ended while we looked
    return found


def memory_kb(pid):
    """(VmRSS, RssAnon) in kB. RSS counts the shared libraries' pages too (RssFile: half of a small node's
    RSS), which come and go with the code a node runs and the page cache, not with its own memory;
    RssAnon is its own (heap, arenas, stacks): what a leak grows."""
    rss = anon = 0
    with open(f"/proc/{pid}/status") as f:
        for line in f:
            if line.startswith("VmRSS:"):
                rss = int(line.split()[1])
            elif line.startswith("RssAnon:"):
                anon = int(line.split()[1])
    return rss, anon


def open_fds(pid):
    return len(os.listdir(f"/proc/{pid}/fd"))


def main():
    if len(sys.argv) < 4:
        sys.exit(__doc__)
    bin_dir, recording, minutes = sys.argv[1], sys.argv[2], float(sys.argv[3])
    extra = sys.argv[4:]
    with tempfile.TemporaryDirectory(prefix="tachi-soak-") as out:
        cmd = [os.path.join(bin_dir, "tachi"), "run", "--recording", recording, "--domain", DOMAIN, "--out", out,
               "--headless", "--set", "sensor.loop=true"] + extra
        print(f"soak: {' '.join(cmd)} for {minutes:g} min")
        # The launcher's log goes to a file: a pipe nobody drains fills after ~64 KiB (~26 minutes of status
        # lines). The launcher blocked on it then (twice: the trace stopped at minute 26); it now drops the
        # lines it cannot write (common/log_sink.hpp), and the file keeps them.
        err_file = open(os.path.join(out, "launcher.err"), "w+")
        run = subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=err_file, text=True)
        start = time.monotonic()
        samples = []  # (minute, node, rss_kb, anon_kb, fds)
        while time.monotonic() - start < minutes * 60.0 and run.poll() is None:
            time.sleep(SAMPLE_S)
            minute = int((time.monotonic() - start) // 60)
            for pid, name in children_of(run.pid).items():
                try:
                    samples.append((minute, name, *memory_kb(pid), open_fds(pid)))
                except OSError:
                    pass  # restarted or ending: the summary's restarts say which
        ended_early = run.poll() is not None
        run.send_signal(signal.SIGINT)
        try:
            run.wait(timeout=30)
        except subprocess.TimeoutExpired:
            run.kill()
            sys.exit("soak: the run did not stop within 30 s of SIGINT")
        err_file.seek(0)
        err = err_file.read()
        err_file.close()
        if ended_early:
            sys.exit(f"soak: the run ended by itself after {time.monotonic() - start:.0f} s (exit {run.returncode}):\n{err[-2000:]}")
        if os.environ.get("TACHI_SOAK_KEEP"):
            shutil.copytree(out, os.environ["TACHI_SOAK_KEEP"], dirs_exist_ok=True)
        summary = json.load(open(os.path.join(out, "summary.json")))
        latency = {}  # minute -> ms
        first_ns = None
        with open(os.path.join(out, "trace", "strokes.csv"), newline="") as f:
            for row in csv.DictReader(f):
                acquired, received = int(row["acquired_ns"]), int(row["received_ns"])
                if acquired <= 0:
                    continue
                first_ns = first_ns or received
                latency.setdefault(int((received - first_ns) // 60_000_000_000), []).append((received - acquired) * 1e-6)

    nodes = sorted({s[1] for s in samples})
    minutes_seen = sorted({s[0] for s in samples})
    per = {}  # (minute, node) -> (median rss MB, median anonymous MB, median fds)
    for m in minutes_seen:
        for n in nodes:
            rows = [s for s in samples if s[0] == m and s[1] == n]
            if rows:
                per[m, n] = (statistics.median(r[2] for r in rows) / 1024.0, statistics.median(r[3] for r in rows) / 1024.0,
                             statistics.median(r[4] for r in rows))
    print("minute  " + "  ".join(f"{n[:14]:>14s} RSS/anon MB/fd" for n in nodes) + "  latency p50/p99 ms (samples)")
    for m in minutes_seen:
        cells = "  ".join(f"{per[m, n][0]:9.1f}/{per[m, n][1]:6.1f}/{per[m, n][2]:3.0f}" if (m, n) in per else f"{'-':>20s}"
                          for n in nodes)
        lat = latency.get(m, [])
        lat_text = f"{pct(lat, 50):6.2f} / {pct(lat, 99):6.2f} ({len(lat)})" if lat else "-"
        print(f"{m:6d}  {cells}  {lat_text}")

    failures = []
    full = [m for m in minutes_seen if m in latency]
    if len(full) < 3:
        failures.append(f"too short to judge: {len(full)} minutes with samples (at least 3)")
    else:
        base = max(full[1], min(full[-2], int(minutes // 6)))
        # The last minute may be partial (the run stops mid-minute): it is judged when nearly whole.
        last = full[-1] if len(latency[full[-1]]) >= 0.8 * len(latency[base]) else full[-2]
        for n in nodes:
            if (base, n) not in per or (last, n) not in per:
                failures.append(f"{n}: not sampled in minutes {base} and {last}")
                continue
            (r0, a0, f0), (r1, a1, f1) = per[base, n], per[last, n]
            growth = (r1 - r0) / r0 * 100.0
            anon_growth = (a1 - a0) / a0 * 100.0 if a0 > 0 else 0.0
            first = per.get((full[1], n), per[base, n])[0]
            print(f"{n}: RSS {r0:.1f} -> {r1:.1f} MB ({growth:+.1f} %), anonymous {a0:.1f} -> {a1:.1f} MB ({anon_growth:+.1f} %), "
                  f"descriptors {f0:.0f} -> {f1:.0f} (minute {base} -> {last}); "
                  f"RSS from minute {full[1]}: {first:.1f} MB ({(r1 - first) / first * 100.0:+.1f} %)")
            # The target is on RSS; anonymous memory (a leak's measure) is judged and reported beside it.
            if growth > 2.0:
                failures.append(f"{n}: RSS grew {growth:.1f} % (> 2 %)")
            if anon_growth > 2.0:
                failures.append(f"{n}: anonymous memory grew {anon_growth:.1f} % (> 2 %)")
            if f1 > f0 * 1.02:
                failures.append(f"{n}: descriptors {f0:.0f} -> {f1:.0f} (> 2 %)")
        p0, p1 = pct(latency[base], 99), pct(latency[last], 99)
        print(f"latency p99: minute {base} {p0:.2f} ms, minute {last} {p1:.2f} ms ({p1 / p0:.2f}x)")
        if p1 > 2.0 * p0:
            failures.append(f"latency p99 {p1:.2f} ms in minute {last} > 2x minute {base}'s {p0:.2f} ms")
    restarts = summary.get("restarts")
    print(f"restarts {restarts}, frames {summary.get('frames')}, hand samples {summary.get('hand_samples')}, "
          f"cuts {summary.get('cuts')}, pieces {summary.get('pieces')}, ended: {summary.get('ended')}")
    if restarts != 0:
        failures.append(f"restarts {restarts}")
    print("PASS" if not failures else "FAIL: " + "; ".join(failures))
    sys.exit(1 if failures else 0)


if __name__ == "__main__":
    main()
