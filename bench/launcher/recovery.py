#!/usr/bin/env python3
"""How long a node killed mid-stroke under `tachi run` takes to come back (docs/reliability.md, "No lost
cuts"): the recording is played through `tachi run`, each node in turn is SIGKILLed once the hand is
cutting, and the launcher's summary gives the recovery (kill -> the restarted node's first heartbeat; for
the simulator, after it replayed its journal). Timing belongs here, not in the tests: the tests check
that the cut survives the kill; this prints how fast it did, with the machine's load beside it.

The kill is timed from the launcher's log: once it started the sensor (the last node), the script waits
until the sensor has played `--kill-at` seconds of the recording (the straight cut's hand is on the cloth
from ~1.5 s to ~3.5 s).

Usage: recovery.py BIN_DIR RECORDING [REPEATS [GRID]]   (domain 148; default 3 repeats, grid 32)
"""
import json
import os
import re
import signal
import statistics
import subprocess
import sys
import tempfile
import time

NODES = ["sensor", "filter", "sim", "viewer"]


def one_run(bin_dir, recording, grid, victim, kill_at_s=2.5):
    with tempfile.TemporaryDirectory(prefix="tachi-recovery-bench-") as out:
        cmd = [os.path.join(bin_dir, "tachi"), "run", "--recording", recording, "--grid", str(grid), "--domain", "148",
               "--out", out, "--headless", "--settle", "1"]
        launcher = subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
        pids, log, sensor_started = {}, "", None
        started = re.compile(r"started tachi-(\w+) \(pid (\d+)\)")
        killed = False
        os.set_blocking(launcher.stderr.fileno(), False)
        while launcher.poll() is None:
            chunk = (launcher.stderr.read() or b"").decode(errors="replace")
            log += chunk
            for node, pid in started.findall(chunk):
                pids.setdefault(node, int(pid))
                if node == "sensor" and sensor_started is None:
                    sensor_started = time.monotonic()
            if not killed and sensor_started and time.monotonic() - sensor_started >= kill_at_s and victim in pids:
                os.kill(pids[victim], signal.SIGKILL)
                killed = True
            time.sleep(0.01)
        log += (launcher.stderr.read() or b"").decode(errors="replace")
        if launcher.returncode != 0 or not killed:
            sys.exit(f"run with {victim} killed failed (exit {launcher.returncode}, killed {killed}):\n{log[-2000:]}")
        summary = json.load(open(os.path.join(out, "summary.json")))
        recoveries = summary.get("recoveries", [])
        if len(recoveries) != 1:
            sys.exit(f"expected one recovery of {victim}, summary has {recoveries}")
        return recoveries[0]["recovery_ms"], summary.get("cut_length_m")


def main():
    if len(sys.argv) < 3:
        sys.exit(__doc__)
    bin_dir, recording = sys.argv[1], sys.argv[2]
    repeats = int(sys.argv[3]) if len(sys.argv) > 3 else 3
    grid = int(sys.argv[4]) if len(sys.argv) > 4 else 32
    print(f"recording {recording}, grid {grid}, {repeats} kills per node; load average {os.getloadavg()[0]:.1f} at start")
    print("node     recovery ms: median   max    (each run)")
    for victim in NODES:
        times = [one_run(bin_dir, recording, grid, victim)[0] for _ in range(repeats)]
        print(f"{victim:8s} {statistics.median(times):19.0f} {max(times):6.0f}    "
              + " ".join(f"{t:.0f}" for t in times))
    print(f"load average {os.getloadavg()[0]:.1f} at the end")


if __name__ == "__main__":
    main()
