#!/usr/bin/env bash
# The CUDA backend (issue 34) on a bare GPU machine, from the repository root:
#
#     bash benchmarks/gpu_check.sh            # (carry .whl: the wheels the machine lacks)
#
# Installs the wheels in .whl/ (pydantic and its kin, meshio) into /tmp/site, then, each part
# independent of the others' failure, everything tee'd into $OUT/*.log (total <= 6 minutes):
#   1. nvidia-smi                                                  -> $OUT/nvidia-smi.log
#   2. CUDA vs CPU backend on the real device (no simulator):      -> $OUT/compare.log
#      the matched dam break and the tutorial selections the device supports (solitaryBeach:
#      mirror ghosts with the paddle), a few hundred steps at a small size (largest relative
#      field difference per case, one JSON line each)
#   3. sphfoam run with backend cuda: a short matched dam break and a short solitaryWave
#                                                                  -> $OUT/run_*.log
#   4. benchmarks/bench_gpu.py at 23k, 400k, 4M particles          -> $OUT/bench.log,
#      $OUT/gpu-*.json and $OUT/gpu-*.md
set -x
export PYTHONUNBUFFERED=1
OUT=${OUT:-/tmp/gpu_check_out}
mkdir -p "$OUT"
ROOT=$PWD
if compgen -G ".whl/*.whl" > /dev/null; then
    python3 -m pip install -q --no-index --no-deps --no-compile --target /tmp/site .whl/*.whl \
        2>&1 | tee "$OUT/install.log"
    export PYTHONPATH=/tmp/site:$ROOT
else
    export PYTHONPATH=$ROOT
fi
export SPHFOAM_CACHE_DIR=/tmp/sphfoam_cache
unset NUMBA_ENABLE_CUDASIM

# 1. the device
nvidia-smi 2>&1 | tee "$OUT/nvidia-smi.log"
python3 -c "from sphfoam.engine.cuda import cuda_module; c = cuda_module(); import numba; print('numba', numba.__version__, c.__file__, 'available', c.is_available()); c.detect()" 2>&1 | tee -a "$OUT/nvidia-smi.log"

# 2. CUDA against CPU on the device, a few hundred steps, small cases (about 40 s each)
(
  timeout 80 python3 tests/cuda_compare.py damBreakMatched --dx 0.04 --steps 300
  timeout 50 python3 tests/cuda_compare.py solitaryWave --dx 0.1 --steps 200
  timeout 120 python3 tests/cuda_compare.py solitaryBeach --dx 0.05 --steps 300
  timeout 50 python3 tests/cuda_compare.py damBreakMatched --dx 0.04 --steps 300 \
      --edits '{"system/sphSchemes:precision": "single"}'
) 2>&1 | tee "$OUT/compare.log"

# 3. sphfoam run with backend cuda (the CLI's --backend)
for c in damBreakMatched solitaryWave; do
  (
    src=$ROOT/benchmarks/cases/$c; [ -d "$src" ] || src=$ROOT/tutorials/$c
    rm -rf "/tmp/run_$c"; cp -r "$src" "/tmp/run_$c"
    timeout 60 python3 -m sphfoam run "/tmp/run_$c" --backend cuda --end-time 0.02 --no-progress
    echo "exit $?"; ls "/tmp/run_$c"
  ) 2>&1 | tee "$OUT/run_$c.log"
done

# 4. the benchmark (about 3 minutes)
timeout 200 python3 benchmarks/bench_gpu.py --sizes 23k,400k,4M --steps 20 --cpu-steps 20 \
    --out "$OUT" 2>&1 | tee "$OUT/bench.log"
ls -la "$OUT"
