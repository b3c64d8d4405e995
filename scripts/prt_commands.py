"""What the figure scripts share: running a prt command and reading its --log-json events.

Each figure script (sweep.py, envlight_figures.py, adapt_figures.py, adapt_size_goal.py) imports this module from
its own folder; none of them needs anything beyond the Python standard library for it.
"""
import hashlib
import json
import os
import subprocess
import sys
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
DATA = os.path.join(ROOT, ".cache", "data")
# Rec. 709 luminance weights of linear RGB, as lib/core/luminance.h.
LUMINANCE = (0.2126, 0.7152, 0.0722)


def run_logged(args, who):
    """Runs a command with its argument list (never through a shell); returns (wall seconds, stdout, [the JSON
    events of its --log-json stderr, other lines skipped]). A non-zero exit ends the script with `who`'s name, the
    command and its stderr."""
    start = time.monotonic()
    result = subprocess.run([str(a) for a in args], check=False, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            text=True)
    seconds = time.monotonic() - start
    if result.returncode != 0:
        sys.exit(f"{who}: {' '.join(str(a) for a in args)} failed ({result.returncode}):\n{result.stderr}")
    events = []
    for line in result.stderr.splitlines():
        try:
            events.append(json.loads(line))
        except ValueError:
            pass
    return seconds, result.stdout, events


def stage_seconds(events, fallback):
    """The stage's own time from its "cost" event, else `fallback` (the wall time)."""
    for event in events:
        if event.get("event") == "cost":
            return float(event["seconds"])
    return fallback


def file_hash(path):
    """SHA-256 of a file's bytes, hex."""
    with open(path, "rb") as f:
        return hashlib.sha256(f.read()).hexdigest()
