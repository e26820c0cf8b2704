#!/usr/bin/env bash
# Packs a CUDA build for a GPU machine that lacks the build machine's packages: the test
# binaries, the app and the benchmarks (stripped), the test data, the shared libraries they need beyond
# glibc/libstdc++ and the NVIDIA driver, and run-tests.sh, which runs every test binary.
# Usage: bash cmake/gpu_bundle.sh [BUILD_DIR (default build/cuda)] [OUT_DIR (default build/cuda-bundle)]
set -euo pipefail
build=${1:-build/cuda}
out=${2:-build/cuda-bundle}
[ -x "$build/apps/perishell" ] || { echo "gpu_bundle: no perishell app in $build; build the cuda preset first" >&2; exit 1; }
rm -rf "$out"; mkdir -p "$out/bin" "$out/lib"
binaries=("$build"/tests/*_test_* "$build/apps/perishell" "$build"/perf/perishell_perf_*)
for b in "${binaries[@]}"; do
  case "$b" in *.cmake) continue ;; esac
  [ -x "$b" ] && strip -o "$out/bin/$(basename "$b")" "$b"
done
# The per-kernel timer (perf/kernel_timer.cpp): KOKKOS_PROFILE_LIBRARY=lib/libperishell_kernel_timer.so.
if [ -f "$build/perf/libperishell_kernel_timer.so" ]; then cp "$build/perf/libperishell_kernel_timer.so" "$out/lib/"; fi
# Every shared library the binaries need (a bare CUDA image may lack BLAS, HDF5 and their
# chains), except the driver, glibc and the C++ runtime, which stay the host's.
for b in "$out"/bin/*; do ldd "$b"; done | awk '$3 ~ /^\// {print $3}' | sort -u |
  grep -vE '/(libc|libm|libdl|libpthread|librt|libresolv|ld-linux-x86-64|libstdc\+\+|libgcc_s|libcuda)\.so' |
  # An MPI build (cuda-mpi) uses the GPU machine's Open MPI 4.1 and NCCL (same sonames; its
  # mpirun must start the ranks with its own runtime and transports): never copied.
  grep -vE '/(libmpi|libopen-(rte|pal)|libnccl|libhwloc|libevent|libpmix|libuc[mpst]|libfabric|libibverbs|librdmacm|libpsm|libnl-|libmunge)[^/]*\.so' |
  # cuSOLVER, cuSPARSE and cuBLAS (hundreds of MB): the GPU machine's CUDA 13 toolkit has them.
  grep -vE '/lib(cusolver|cusparse|cublas|cublasLt|nvJitLink)\.so' |
  while read -r lib; do cp -L "$lib" "$out/lib/"; done
cp -r "$(dirname "${BASH_SOURCE[0]}")/../tests/data" "$out/data"
cat > "$out/run-tests.sh" <<'SCRIPT'
#!/usr/bin/env bash
# Runs every test binary of the bundle (CUDA and OpenMP categories); exit 1 if any fails.
cd "$(dirname "$0")"
export LD_LIBRARY_PATH="$PWD/lib:/usr/local/cuda/lib64${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}"
export PERISHELL_TEST_DATA_DIR="$PWD/data"
failed=0
for t in bin/*_test_*; do
  echo "=== $t"
  "$t" "$@" || { echo "FAILED: $t"; failed=1; }
done
exit $failed
SCRIPT
chmod +x "$out/run-tests.sh"
du -sh "$out"
