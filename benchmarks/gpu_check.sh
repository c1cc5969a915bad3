#!/usr/bin/env bash
# The CUDA backend (issue 34) on a bare GPU machine, from the repository root, in two parts
# that each fit one call of a few minutes:
#
#     bash benchmarks/gpu_check.sh check     # the comparisons, then the benchmarks (~5 min)
#     bash benchmarks/gpu_check.sh runs      # tutorials end to end, the precision trade (~4 min)
#
# Wheels the machine lacks (pydantic and its kin, meshio) are installed from .whl/ when it
# is there. Everything goes to $OUT (default /tmp/gpu_check_out):
#   check: check.log (the device, the install, everything printed), compare.json (every
#          tutorial's selection against the CPU backend, benchmarks/gpu_compare.py),
#          gpu-<date>.{json,md} and gpu-<date>-3d.{json,md} (benchmarks/bench_gpu.py: the
#          matched dam break in 2-D at 23 k to 16 M particles and in 3-D at 131 k to ~4 M,
#          each alone on the device)
#   runs:  runs.log, run_solitaryWave.log, run_solitaryBeach.log (sphfoam run --backend
#          cuda: the README's flume and the beach, as far as the part's minutes go),
#          precision.json (benchmarks/precision_study.py --backend cuda)
set -x
export PYTHONUNBUFFERED=1
OUT=${OUT:-/tmp/gpu_check_out}
mkdir -p "$OUT"
ROOT=$PWD
PART=${1:-check}
LOG="$OUT/$PART.log"
if compgen -G ".whl/*.whl" > /dev/null; then
    python3 -m pip install -q --no-index --no-deps --no-compile --no-cache-dir --upgrade \
        --target /tmp/site .whl/*.whl 2>&1 | tee -a "$LOG"
    export PYTHONPATH=/tmp/site:$ROOT
else
    export PYTHONPATH=$ROOT
fi
export SPHFOAM_CACHE_DIR=/tmp/sphfoam_cache
unset NUMBA_ENABLE_CUDASIM

if [ "$PART" = check ]; then
  (
    nvidia-smi
    python3 -c "import numba, importlib.metadata as m; from sphfoam.engine.cuda import cuda_module; c = cuda_module(); print('numba', numba.__version__, 'numba-cuda', m.version('numba-cuda')); c.detect()"
    python3 -c "import sphfoam.cli" && echo "sphfoam imports"
    # 1. every tutorial's selection, CUDA against CPU, a few hundred steps (side by side)
    timeout 210 python3 benchmarks/gpu_compare.py --jobs 14 --timeout 190 \
        --out "$OUT/compare.json"
    # 2. the matched dam break, alone on the device
    timeout 170 python3 benchmarks/bench_gpu.py --dim 2 --sizes 23k,400k,4.5M,16M \
        --steps 20 --precision double,single --budget 150 --cpu-steps 20 --out "$OUT"
    timeout 100 python3 benchmarks/bench_gpu.py --dim 3 --sizes 131k,1.4M,5.5M \
        --steps 10 --precision double --budget 85 --cpu-steps 5 --out "$OUT"
    ls -la "$OUT"
  ) 2>&1 | tee -a "$LOG"
elif [ "$PART" = runs ]; then
  (
    for c in solitaryWave solitaryBeach; do
      (
        rm -rf "/tmp/run_$c"; cp -r "$ROOT/tutorials/$c" "/tmp/run_$c"
        python3 -m sphfoam setup "/tmp/run_$c" && \
        timeout 200 python3 -m sphfoam run "/tmp/run_$c" --backend cuda --no-progress
        echo "exit $?"; ls "/tmp/run_$c"; tail -5 "/tmp/run_$c"/postProcessing/*/*/*.dat
      ) > "$OUT/run_$c.log" 2>&1 &
    done
    timeout 200 python3 benchmarks/precision_study.py --backend cuda --out "$OUT/precision.json"
    wait
    tail -30 "$OUT"/run_*.log
  ) 2>&1 | tee -a "$LOG"
fi
