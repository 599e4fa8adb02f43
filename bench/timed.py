#!/usr/bin/python3
"""Runs a command and writes its wall seconds (to 0.1 ms) and peak RSS (KiB) to a file, as
"WALL RSS"; the command's output passes through, its exit code is returned.
usage: timed.py OUT_FILE COMMAND [ARG...]"""
import resource, subprocess, sys, time
if len(sys.argv) < 3:
    sys.exit("usage: timed.py OUT_FILE COMMAND [ARG...]")
out, command = sys.argv[1], sys.argv[2:]
start = time.perf_counter()
code = subprocess.call(command)
wall = time.perf_counter() - start
with open(out, "w") as f:
    f.write("%.4f %d\n" % (wall, resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss))
sys.exit(code if code >= 0 else 128 - code)  # killed by signal N: 128 + N, as a shell says
