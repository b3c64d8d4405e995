#!/usr/bin/env bash
# The farm run of docs/results.md ("Farm run on Slurm"): N instances of the bunny over a floor through
# pipelines/farm.toml (interreflected, order 5, 2 bounces, 16 shards) with `prt run --executor slurm` on a private
# single-node Slurm (scripts/slurm_local.sh; needs root, munge and slurm-wlm), then the same unsharded with the
# local executor, and the two bundles compared byte for byte. Run from the repository root after building prt.
#   scripts/farm_run.sh N [SAMPLES] [--no-unsharded]
# Leaves out/farm/ (outputs), .cache/farm/ (scene, caches, reports, figures.txt).
set -euo pipefail
count=${1:?usage: scripts/farm_run.sh N [SAMPLES] [--no-unsharded]}
samples=${2:-64}
unsharded=${3:-}
prt=$(realpath build/prt)
work=.cache/farm
mkdir -p "$work" out/farm
[ -f .cache/data/bunny.ply ] || { echo "missing .cache/data/bunny.ply (scripts/bootstrap.sh)" >&2; exit 1; }
[ -f "$work/bunny.glb" ] || "$prt" --quiet meshprep .cache/data/bunny.ply -o "$work/bunny.glb"
python3 scripts/instanced_scene.py "$work/bunny.glb" "$count" "$work/scene.glb"
pipeline="$work/farm-$count-$samples.toml"
sed "s/^samples = 64/samples = $samples/" pipelines/farm.toml > "$pipeline"

slurm=$(mktemp -d /tmp/prt-farm-slurm-XXXXXX)
trap 'scripts/slurm_local.sh stop "$slurm" >/dev/null 2>&1 || true' EXIT
conf=$(scripts/slurm_local.sh start "$slurm" | tail -1)
export SLURM_CONF=$conf
figures="$work/figures-$count-$samples.txt"
: > "$figures"
rm -f "$work"/report-*.json "$work"/time-*.txt # figures of this run only
rm -rf "$work/cache-slurm"
# The farm run, intermediates kept so that the store can be measured before and after `prt gc`.
/usr/bin/time -v -o "$work/time-slurm.txt" "$prt" run "$pipeline" --executor slurm --cache-dir "$work/cache-slurm" \
  --keep-intermediates --report "$work/report-slurm.json" --allow-outputs-anywhere
echo "store before gc: $(du -sb "$work/cache-slurm/store" | cut -f1) bytes" >> "$figures"
"$prt" gc --cache-dir "$work/cache-slurm" >> "$figures"
echo "store after gc: $(du -sb "$work/cache-slurm/store" | cut -f1) bytes" >> "$figures"
echo "outputs: $(du -sb out/farm | cut -f1) bytes" >> "$figures"
cp out/farm/farm.prt.glb "$work/farm-sharded.prt.glb"
/usr/bin/time -f "cached rerun %e s" -a -o "$figures" "$prt" --quiet run "$pipeline" --executor slurm \
  --cache-dir "$work/cache-slurm" --allow-outputs-anywhere
if [ "$unsharded" != "--no-unsharded" ]; then
  rm -rf "$work/cache-local"
  /usr/bin/time -v -o "$work/time-local.txt" "$prt" run "$pipeline" --shards 1 --threads 2 --cache-dir "$work/cache-local" \
    --report "$work/report-local.json" --allow-outputs-anywhere
  if cmp -s out/farm/farm.prt.glb "$work/farm-sharded.prt.glb"; then echo "sharded == unsharded: byte-identical" >> "$figures"
  else echo "sharded != unsharded" >> "$figures"; fi
fi
python3 - "$work" "$figures" <<'PY'
import json, sys
work, figures = sys.argv[1], sys.argv[2]
out = open(figures, "a")
for name in ("slurm", "local"):
    try: report = json.load(open(f"{work}/report-{name}.json"))
    except OSError: continue
    print(f"{name}: wall {report['seconds']:.1f} s", file=out)
    for stage in report["stages"]:
        jobs = stage.get("shard_jobs", [])
        line = f"  {stage['id']}: {stage['status']} {stage.get('seconds', 0):.1f} s peak {stage.get('peak_memory_bytes', 0) / 2**20:.0f} MiB"
        if jobs:
            kinds = {}
            for job in jobs:
                kind = job["shard"] if isinstance(job["shard"], str) else "shard"
                kind = f"pass {job.get('pass', '')} {kind}".strip()
                k = kinds.setdefault(kind, [0, 0.0, 0])
                k[0] += 1; k[1] += job["seconds"]; k[2] = max(k[2], job["peak_memory_bytes"])
            line += "; job seconds summed %.1f" % sum(j["seconds"] for j in jobs)
            for kind, (n, s, p) in kinds.items():
                line += f"\n    {kind}: {n} jobs, {s:.1f} s summed, peak {p / 2**20:.0f} MiB"
        print(line, file=out)
PY
for t in slurm local; do
  [ -f "$work/time-$t.txt" ] && grep -E "Elapsed|User time|System time|Maximum resident" "$work/time-$t.txt" | sed "s/^/$t prt run: /" >> "$figures"
done
cat "$figures"
