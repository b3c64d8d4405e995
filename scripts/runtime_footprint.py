#!/usr/bin/python3
"""The thin runtime's footprint: what the installed-runtime consumer (tests/runtime/consumer, built by ctest's
runtime_install_consumer) and `prt --version` load and how long they take to start.

usage: scripts/runtime_footprint.py BUILD_DIR [BUILD_DIR ...] [--runs N] [--json OUT.json]

For each build folder it prints the consumer's shared libraries (ldd), which of OpenImageIO, TBB, Embree, Ceres,
OpenCL, OpenEXR it pulls in, its size in bytes, and the median wall time of N runs of the consumer and of
`prt --version` (start-up is mostly the dynamic loader mapping and relocating shared libraries). Run ctest -R
runtime_install_consumer first so the consumer exists. Give two folders (after, before) to compare builds."""
import json
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

HEAVY = ["OpenImageIO", "tbb", "embree", "ceres", "OpenCL", "OpenEXR", "xxhash"]


def median_seconds(command, runs):
    """(median, minimum) wall seconds of `runs` runs; on a shared machine the minimum is the steadier figure."""
    times = []
    for _ in range(runs):
        start = time.perf_counter()
        subprocess.run(command, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, check=True)
        times.append(time.perf_counter() - start)
    return statistics.median(times), min(times)


def libraries(binary):
    out = subprocess.run(["ldd", str(binary)], capture_output=True, text=True, check=True).stdout
    return [line.split()[0] for line in out.splitlines() if line.strip()]


def measure(build, runs):
    build = Path(build)
    consumer = build / "tests/runtime/install_consumer/build/consumer"
    prt = build / "prt"
    row = {"build": str(build)}
    if consumer.exists():
        libs = libraries(consumer)
        with tempfile.TemporaryDirectory() as scratch:
            row["consumer"] = {
                "shared_libraries": len(libs),
                "heavy": [h for h in HEAVY if any(h.lower() in lib.lower() for lib in libs)],
                "libraries": libs,
                "bytes": consumer.stat().st_size,
                "run_seconds_median_min": median_seconds([str(consumer), scratch + "/c.glb"], runs),
            }
    driver = build / "prt-driver"
    if driver.exists():  # the real driver behind the `prt` launcher: what every stage still loads
        row["prt_driver"] = {
            "shared_libraries": len(libraries(driver)),
            "version_seconds_median_min": median_seconds([str(driver), "--version"], runs),
        }
    if prt.exists():
        row["prt"] = {
            "shared_libraries": len(libraries(prt)),
            "bytes": prt.stat().st_size,
            "version_seconds_median_min": median_seconds([str(prt), "--version"], runs),
        }
    return row


def main():
    args = sys.argv[1:]
    runs, out = 20, None
    if "--runs" in args:
        i = args.index("--runs")
        runs = int(args[i + 1])
        del args[i:i + 2]
    if "--json" in args:
        i = args.index("--json")
        out = args[i + 1]
        del args[i:i + 2]
    if not args:
        print(__doc__, file=sys.stderr)
        sys.exit(2)
    rows = [measure(build, runs) for build in args]
    for row in rows:
        c, p = row.get("consumer"), row.get("prt")
        line = row["build"] + ":"
        if c:
            med, low = c["run_seconds_median_min"]
            line += (f" consumer {c['shared_libraries']} shared libraries (heavy: {', '.join(c['heavy']) or 'none'}),"
                     f" {c['bytes']} bytes, run median {1e3 * med:.1f} ms (min {1e3 * low:.1f});")
        if p:
            med, low = p["version_seconds_median_min"]
            line += (f" prt {p['shared_libraries']} shared libraries, --version median {1e3 * med:.1f} ms"
                     f" (min {1e3 * low:.1f});")
        d = row.get("prt_driver")
        if d:
            med, low = d["version_seconds_median_min"]
            line += f" prt-driver {d['shared_libraries']} shared libraries, --version median {1e3 * med:.1f} ms (min {1e3 * low:.1f})"
        print(line)
    if out:
        Path(out).write_text(json.dumps({"runs": runs, "builds": rows}, indent=2) + "\n")


if __name__ == "__main__":
    main()
