#!/usr/bin/python3
"""Memory and log soak of a launch file (a measurement, not a test: machines are shared).

Runs `roslaunch <launch file> <args>` on a master of its own for a given wall time, samples the
resident memory (RSS) of every process the launch started once per `--period` seconds, and prints
per node the RSS after the warm-up (the first sample after `--warmup` seconds) and at the end, the
growth in per cent, plus every ERROR/FATAL line and every line matching `--count` in the logs.

  launch_soak.py --seconds 600 launch/simulation.launch speed:=10
  launch_soak.py --seconds 60 --count 'restart' launch/playback.launch bag:=$PWD/test/data/session/session.bag loop:=true

Exit status 1 when a node's RSS grew by more than `--max-growth` per cent or an ERROR/FATAL line
was logged.
"""
import argparse
import os
import re
import signal
import socket
import subprocess
import sys
import tempfile
import time


def children(pid):
    """All descendants of pid (from /proc/<pid>/task/*/children)."""
    found, stack = [], [pid]
    while stack:
        p = stack.pop()
        try:
            for task in os.listdir(f"/proc/{p}/task"):
                with open(f"/proc/{p}/task/{task}/children") as f:
                    kids = [int(k) for k in f.read().split()]
                found += kids
                stack += kids
        except OSError:
            continue
    return found


def name_and_rss_kib(pid):
    try:
        with open(f"/proc/{pid}/cmdline", "rb") as f:
            argv = [a.decode(errors="replace") for a in f.read().split(b"\0") if a]
        with open(f"/proc/{pid}/status") as f:
            rss = next(int(line.split()[1]) for line in f if line.startswith("VmRSS:"))
    except (OSError, StopIteration):
        return None
    name = next((a.split(":=", 1)[1] for a in argv if a.startswith("__name:=")), None)
    if name is None:
        name = os.path.basename(argv[0]) if argv else str(pid)
    return name, rss


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--seconds", type=float, default=600.0, help="wall time to run [s]")
    parser.add_argument("--warmup", type=float, default=30.0, help="wall time before the first reference sample [s]")
    parser.add_argument("--period", type=float, default=5.0, help="sampling period [s]")
    parser.add_argument("--max-growth", type=float, default=5.0, help="allowed RSS growth per node [%%]")
    parser.add_argument("--count", action="append", default=[], help="regular expression to count in the logs")
    parser.add_argument("launch", nargs=argparse.REMAINDER, help="launch file and its arguments")
    args = parser.parse_args()
    if not args.launch:
        parser.error("no launch file")
    with socket.socket() as s:
        s.bind(("localhost", 0))
        port = s.getsockname()[1]
    log_dir = tempfile.mkdtemp(prefix="launch_soak_")
    env = dict(os.environ, ROS_MASTER_URI=f"http://localhost:{port}", ROS_LOG_DIR=log_dir)
    console = open(os.path.join(log_dir, "roslaunch_console.log"), "w")
    launch = subprocess.Popen(["roslaunch", "-p", str(port)] + args.launch, env=env, stdin=subprocess.DEVNULL,
                              stdout=console, stderr=subprocess.STDOUT, start_new_session=True)
    start = time.monotonic()
    reference, last = {}, {}
    try:
        while time.monotonic() - start < args.seconds and launch.poll() is None:
            time.sleep(args.period)
            sample = {}
            for pid in children(launch.pid):
                entry = name_and_rss_kib(pid)
                if entry and entry[0] not in ("rosmaster", "rosout"):
                    sample[entry[0]] = sample.get(entry[0], 0) + entry[1]
            if not reference and time.monotonic() - start >= args.warmup:
                reference = dict(sample)
            last = sample
    finally:
        ended_early = launch.poll() is not None
        if not ended_early:
            os.killpg(launch.pid, signal.SIGINT)
            try:
                launch.wait(timeout=30)
            except subprocess.TimeoutExpired:
                os.killpg(launch.pid, signal.SIGKILL)
        console.close()
    elapsed = time.monotonic() - start
    print(f"launch_soak: {' '.join(args.launch)}: {elapsed:.0f} s wall, load {os.getloadavg()[0]:.1f}, logs {log_dir}")
    status = 0
    if ended_early:
        print(f"  the launch ended by itself after {elapsed:.0f} s (exit {launch.returncode})")
        status = 1
    for name in sorted(reference):
        if name not in last:
            print(f"  {name}: gone before the end")
            status = 1
            continue
        growth = 100.0 * (last[name] - reference[name]) / max(reference[name], 1)
        flag = "" if growth <= args.max_growth else "  <-- above the bound"
        status = status or int(growth > args.max_growth)
        print(f"  {name}: RSS {reference[name] / 1024:.1f} MiB after warm-up, {last[name] / 1024:.1f} MiB at the end"
              f" ({growth:+.1f} %){flag}")
    patterns = [re.compile(p) for p in args.count]
    counts = [0] * len(patterns)
    errors = []
    # rosout.log holds every node's messages once (the per-node logs and the console repeat them).
    logs = [os.path.join(root, f) for root, _, files in os.walk(log_dir) for f in files if f == "rosout.log"]
    for path in logs or [os.path.join(log_dir, "roslaunch_console.log")]:
        with open(path, errors="replace") as f:
            for line in f:
                if re.search(r"\b(ERROR|FATAL)\b", line):
                    errors.append(line.strip())
                for i, p in enumerate(patterns):
                    counts[i] += bool(p.search(line))
    for p, n in zip(args.count, counts):
        print(f"  log lines matching '{p}': {n}")
    print(f"  ERROR/FATAL lines: {len(errors)}")
    for line in errors[:10]:
        print(f"    {line[:300]}")
    return 1 if errors else status


if __name__ == "__main__":
    sys.exit(main())
