#!/usr/bin/env python3
"""Runs a command and samples its resident memory (VmRSS, of it and its child processes) through the run.

usage: memory_watch.py [--every S] [--csv FILE] [--kill-after S] -- COMMAND [ARGS...]

Prints one line of JSON: the command's exit code, its wall time, the peak resident memory, the resident memory
at a quarter, half, three quarters and the end of the run, and the growth over the run's second half (MiB per
minute, a least-squares slope), and writes every sample (seconds, MiB) to --csv. A run whose memory is flat
after it has warmed up shows a second-half slope near zero. --kill-after sends SIGKILL to the command (and its
children) that many seconds after its start, as a crash would: the exit code is then -9.
"""
import argparse
import json
import os
import signal
import subprocess
import sys
import time


def descendants(pid):
    """pid and every process below it, from /proc."""
    children = {}
    for entry in os.listdir("/proc"):
        if not entry.isdigit():
            continue
        try:
            with open(f"/proc/{entry}/stat") as f:
                fields = f.read().rsplit(")", 1)[1].split()
            children.setdefault(int(fields[1]), []).append(int(entry))
        except (OSError, IndexError, ValueError):
            continue  # a process that ended meanwhile
    found, todo = [], [pid]
    while todo:
        p = todo.pop()
        found.append(p)
        todo += children.get(p, [])
    return found


def resident_mib(pids):
    total = 0
    for p in pids:
        try:
            with open(f"/proc/{p}/status") as f:
                for line in f:
                    if line.startswith("VmRSS:"):
                        total += int(line.split()[1])  # kB
                        break
        except OSError:
            continue
    return total / 1024.0


def slope(samples):
    """Least-squares MiB per minute of (seconds, MiB) samples."""
    if len(samples) < 2:
        return 0.0
    n = len(samples)
    mt = sum(t for t, _ in samples) / n
    mm = sum(m for _, m in samples) / n
    var = sum((t - mt) ** 2 for t, _ in samples)
    if var == 0:
        return 0.0
    return 60.0 * sum((t - mt) * (m - mm) for t, m in samples) / var


def at(samples, fraction):
    """The sample nearest to `fraction` of the run's duration."""
    end = samples[-1][0]
    return min(samples, key=lambda s: abs(s[0] - fraction * end))[1]


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--every", type=float, default=0.5, help="seconds between samples")
    parser.add_argument("--csv", help="write every sample here")
    parser.add_argument("--kill-after", type=float, help="SIGKILL the command after this many seconds")
    parser.add_argument("command", nargs=argparse.REMAINDER)
    args = parser.parse_args()
    command = args.command[1:] if args.command[:1] == ["--"] else args.command
    if not command:
        parser.error("expected a command after --")
    began = time.monotonic()
    process = subprocess.Popen(command, start_new_session=True)
    samples = []
    while process.poll() is None:
        now = time.monotonic() - began
        samples.append((now, resident_mib(descendants(process.pid))))
        if args.kill_after is not None and now >= args.kill_after:
            os.killpg(process.pid, signal.SIGKILL)
            process.wait()
            break
        time.sleep(args.every)
    wall = time.monotonic() - began
    samples = [s for s in samples if s[1] > 0] or [(0.0, 0.0)]
    if args.csv:
        with open(args.csv, "w") as f:
            f.write("seconds,rss_mib\n")
            for t, m in samples:
                f.write(f"{t:.3f},{m:.1f}\n")
    half = [s for s in samples if s[0] >= samples[-1][0] / 2]
    print(json.dumps({
        "command": " ".join(command), "exit_code": process.returncode, "wall_s": round(wall, 2),
        "samples": len(samples), "peak_mib": round(max(m for _, m in samples), 1),
        "mib_at_25_50_75_100": [round(at(samples, f), 1) for f in (0.25, 0.5, 0.75, 1.0)],
        "second_half_mib_per_min": round(slope(half), 2)}))
    return 0


if __name__ == "__main__":
    sys.exit(main())
