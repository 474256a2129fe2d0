#!/bin/sh
# Parallel efficiency of a run across processes (issue 36, docs/performance.md "Runs across
# processes"): the 100k periodic box (cases/bench_periodic_box.toml, 99 856 particles, leapfrog)
# for 207 steps as 1 process x P threads and as P processes x 1 thread, alternated, R rounds; the
# run loop's wall time (summary.json: the integration and the two frames, not the scene's build).
# Prints each run and the ratio of the medians: efficiency = t(1 x P) / t(P x 1).
# CASE isph: the ISPH hydrostatic tank (cases/hydrostatic_tank_isph.toml) at dx = 5e-4 m
# (40 000 fluid particles, 200 x 200; walls 5 layers), 20 leapfrog steps, each with a pressure
# solve (BiCGSTAB + BoomerAMG, across the processes in one hypre system).
#   sh tools/bench_distributed.sh [P] [ROUNDS] [VESPH] [CASE]     (defaults 2, 3, build/vesph, box)
set -eu
P=${1:-2}
ROUNDS=${2:-3}
VESPH=${3:-build/vesph}
CASE=${4:-box}
SCENE=$(dirname "$0")/../cases/bench_periodic_box.toml
set -- --set time.end=0.007
if [ "$CASE" = isph ]; then
  SCENE=$(dirname "$0")/../cases/hydrostatic_tank_isph.toml
  set -- --set particles.spacing=5e-4 --set 'domain.min=[-0.0025,-0.0025]' --set 'domain.max=[0.1025,0.12]' \
    --set 'blocks[1].min=[-0.0025,-0.0025]' --set 'blocks[1].max=[0.1025,0.0]' --set 'blocks[2].min=[-0.0025,0.0]' \
    --set 'blocks[3].max=[0.1025,0.12]' --set solver.linear_solver=bicgstab --set integrator.step=8e-5 \
    --set time.end=0.0016 --set output.interval=0.0016
fi
OUT=$(mktemp -d)
trap 'rm -rf "$OUT"' EXIT
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMPI_MCA_rmaps_base_oversubscribe=1
wall() { /usr/bin/python3 -c "import json, sys; print(json.load(open(sys.argv[1]))['wall_seconds'])" "$1/summary.json"; }
threads="" procs=""
r=1
while [ "$r" -le "$ROUNDS" ]; do
  OMP_NUM_THREADS=$P "$VESPH" run "$SCENE" -o "$OUT/threads" --quiet "$@" >/dev/null 2>&1
  a=$(wall "$OUT/threads")
  OMP_NUM_THREADS=1 mpiexec --bind-to none -n "$P" "$VESPH" run "$SCENE" -o "$OUT/procs" --quiet "$@" >/dev/null 2>&1
  b=$(wall "$OUT/procs")
  echo "round $r: 1 process x $P threads $a s, $P processes x 1 thread $b s"
  threads="$threads $a" procs="$procs $b"
  r=$((r + 1))
done
/usr/bin/python3 - "$threads" "$procs" "$P" <<'PY'
import statistics, sys
a = [float(x) for x in sys.argv[1].split()]
b = [float(x) for x in sys.argv[2].split()]
ma, mb = statistics.median(a), statistics.median(b)
print(f"median: 1 x {sys.argv[3]} threads {ma:.3f} s, {sys.argv[3]} x 1 thread {mb:.3f} s: "
      f"efficiency of the processes against the threads {ma / mb:.3f}")
PY
