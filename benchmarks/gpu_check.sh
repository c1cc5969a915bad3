#!/usr/bin/env bash
# The CUDA backend (issue 34) on a bare GPU machine, from the repository root:
#
#     bash benchmarks/gpu_check.sh [all|compare|runs|bench]     # all: about 7 minutes
#
# Wheels the machine lacks (pydantic and its kin, meshio) are installed from .whl/ when it
# is there. Phases (each part of `all`, or one alone for a rerun); everything goes to $OUT
# (default /tmp/gpu_check_out):
#   runs     in the background from the start: the README's flume and the beach tutorial,
#            set up and run with `sphfoam run --backend cuda` (as far as 170 s go):
#            run_solitaryWave.log, run_solitaryBeach.log
#   compare  every tutorial's selection against the CPU backend, a few hundred steps each,
#            side by side (benchmarks/gpu_compare.py); then the precision
#            trade on the device (benchmarks/precision_study.py), tables in check.log
#   bench    once the runs are done, alone on the device: the matched dam break in 2-D at
#            23 k to 16 M particles and in 3-D at 131 k to ~4 M (benchmarks/bench_gpu.py):
#            gpu-<date>.{json,md}, gpu-<date>-3d.{json,md}
# and check.log: the device, the install and everything printed.
set -x
export PYTHONUNBUFFERED=1
OUT=${OUT:-/tmp/gpu_check_out}
mkdir -p "$OUT"
ROOT=$PWD
PART=${1:-all}
LOG="$OUT/check.log"
if compgen -G ".whl/*.whl" > /dev/null; then
    python3 -m pip install -q --no-index --no-deps --no-compile --no-cache-dir --upgrade \
        --target /tmp/site .whl/*.whl 2>&1 | tee -a "$LOG"
    export PYTHONPATH=/tmp/site:$ROOT
else
    export PYTHONPATH=$ROOT
fi
export SPHFOAM_CACHE_DIR=/tmp/sphfoam_cache
unset NUMBA_ENABLE_CUDASIM
want() { [ "$PART" = all ] || [ "$PART" = "$1" ]; }

(
  nvidia-smi
  python3 -c "import numba, importlib.metadata as m; from sphfoam.engine.cuda import cuda_module; c = cuda_module(); print('numba', numba.__version__, 'numba-cuda', m.version('numba-cuda')); c.detect()"
  python3 -c "import sphfoam.cli" && echo "sphfoam imports"
  nproc
) 2>&1 | tee -a "$LOG"

if want runs; then
  for c in solitaryWave solitaryBeach; do
    (
      rm -rf "/tmp/run_$c"; cp -r "$ROOT/tutorials/$c" "/tmp/run_$c"
      date +%s.%N
      python3 -m sphfoam setup "/tmp/run_$c"
      date +%s.%N
      timeout 170 python3 -m sphfoam run "/tmp/run_$c" --backend cuda --no-progress
      echo "exit $?"; date +%s.%N; ls "/tmp/run_$c"
      for f in "/tmp/run_$c"/postProcessing/*/*/*.dat; do echo "== $f"; tail -3 "$f"; done
    ) > "$OUT/run_$c.log" 2>&1 &
  done
fi

if want compare; then
  (
    timeout 150 python3 benchmarks/gpu_compare.py --jobs 12 --timeout 140 \
        --out /tmp/compare.json
    timeout 90 python3 benchmarks/precision_study.py --backend cuda \
        --out /tmp/precision.json
  ) 2>&1 | tee -a "$LOG"
fi

wait          # the runs: the benchmark has the device to itself
tail -25 "$OUT"/run_*.log 2>/dev/null | tee -a "$LOG"

if want bench; then
  (
    timeout 150 python3 benchmarks/bench_gpu.py --dim 2 --sizes 23k,400k,4.5M,16M \
        --steps 20 --precision double,single --budget 130 --cpu-steps 20 --out "$OUT"
    timeout 80 python3 benchmarks/bench_gpu.py --dim 3 --sizes 131k,1.4M,5.5M \
        --steps 10 --precision double --budget 65 --cpu-steps 5 --out "$OUT"
  ) 2>&1 | tee -a "$LOG"
fi
ls -la "$OUT" | tee -a "$LOG"
