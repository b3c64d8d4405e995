#!/usr/bin/python3
"""Draws a `prt run` report as a timeline: one bar per stage (and per shard job) from its start to its end,
coloured by what happened to it, labelled with its time, rays and peak memory.

    scripts/timeline_chart.py .cache/runs/default-.../report.json -o timeline.png

Debian's python3 with python3-matplotlib (see SETUP.md): the pyenv python first on PATH cannot import it.
"""
import argparse
import json
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402 (the backend must be chosen first)

COLOURS = {"ran": "#3b75af", "cached": "#b0b0b0", "failed": "#c03b26", "not run": "#ffffff"}


def label(job):
    parts = ["%.2f s" % job.get("seconds", 0.0)]
    if job.get("rays"):
        parts.append("%.1f Mrays" % (job["rays"] / 1e6))
    if job.get("peak_memory_bytes"):
        parts.append("%.0f MiB" % (job["peak_memory_bytes"] / 2**20))
    return ", ".join(parts)


def rows(report):
    """(name, start, end, status, text) per bar, stages in run order, each followed by its shard jobs."""
    for stage in report["stages"]:
        start, end = stage.get("start"), stage.get("end")
        status = stage["status"]
        if start is None:  # a stage served from the cache before anything ran takes no time
            start = end = 0.0
        yield stage["id"], start, end, status, status if status != "ran" else label(stage)
        for job in stage.get("shard_jobs", []):
            shard = job["shard"]
            name = "  merge" if shard == "merge" else "  shard %d/%d" % (shard[0] + 1, shard[1])
            yield name, job["start"], job["end"], job["status"], label(job) if job["status"] == "ran" else job["status"]


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("report", help="report.json written by `prt run`")
    parser.add_argument("-o", "--output", default="timeline.png", help="PNG to write (default timeline.png)")
    args = parser.parse_args()
    with open(args.report) as f:
        report = json.load(f)

    bars = list(rows(report))
    total = max([report.get("seconds", 0.0)] + [end for _, _, end, _, _ in bars]) or 1.0
    figure, axes = plt.subplots(figsize=(9, 0.45 * len(bars) + 1.4))
    for y, (name, start, end, status, text) in enumerate(bars):
        width = max(end - start, total * 0.004)  # cached stages still show as a sliver
        axes.barh(y, width, left=start, color=COLOURS.get(status, "#888888"), edgecolor="#333333", linewidth=0.5)
        axes.text(start + width + total * 0.01, y, text, va="center", fontsize=8)
    axes.set_yticks(range(len(bars)))
    axes.set_yticklabels([name for name, *_ in bars], fontsize=9)
    axes.invert_yaxis()
    axes.set_xlim(0, total * 1.35)
    axes.set_xlabel("seconds since the run started")
    hits, ran = report.get("cache_hits", 0), report.get("stages_run", 0)
    axes.set_title("%s (%s): %d ran, %d cached, %.2f s%s" % (
        report.get("pipeline", "?"), report.get("executor", "?"), ran, hits, report.get("seconds", 0.0),
        "" if report.get("ok", True) else ", FAILED"), fontsize=10)
    handles = [plt.Rectangle((0, 0), 1, 1, color=c, ec="#333333", lw=0.5) for c in COLOURS.values()]
    axes.legend(handles, COLOURS.keys(), loc="lower right", fontsize=8)
    figure.tight_layout()
    figure.savefig(args.output, dpi=120)
    print(args.output)


if __name__ == "__main__":
    sys.exit(main())
