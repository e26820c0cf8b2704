#!/usr/bin/env bash
# Builds perishell's dependency stack from Debian's Trilinos 13.2 source package:
#   Kokkos 3.4.01 (OpenMP, or CUDA + OpenMP host), Kokkos Kernels 3.4.01 (no ETI, no vendor TPLs),
#   Teuchos + Belos 13.2 (host only, no MPI, no Kokkos inside Trilinos).
# Installs go into a cache keyed by a hash of versions, patches, compilers and build flags;
# a warm cache rebuilds nothing. Why this route: ../shared/docs/deps.md.
#
# Usage: cmake/deps/bootstrap.sh [--backend openmp|cuda] [--cache DIR] [--jobs N]
#                                [--prefix-file FILE] [--no-apt] [--patches DIR] [--with-mpi]
#   --with-mpi: also Debian's Open MPI and METIS, for the openmp-mpi / cuda-mpi presets
#               (docs/parallel.md); nothing in the cache depends on them
#   --patches DIR: apply the patches in DIR instead of cmake/patches (they enter the cache key)
# Environment: PERISHELL_CACHE (cache root, default $HOME/.cache/perishell),
#              PERISHELL_TRILINOS_TARBALL (use this trilinos_13.2.0.orig.tar.gz, skip the download),
#              CXX / CC (host compilers, default g++ / gcc), CUDA_HOME (default /usr/local/cuda).
set -euo pipefail

readonly TRILINOS_DEB_VERSION="13.2.0-4"
readonly TRILINOS_TARBALL_NAME="trilinos_13.2.0.orig.tar.gz"
readonly TRILINOS_TARBALL_SHA256="0ddb47784ba7b8a6b9a07a4822b33be508feb4ccd54301b2a5d10c9e54524b90"
readonly TRILINOS_TOP="Trilinos-trilinos-release-13-2-0"
# What is extracted besides the top-level files (the whole tarball is 830 MB).
readonly TRILINOS_PARTS=(cmake commonTools/build_stats packages/kokkos packages/kokkos-kernels
                         packages/teuchos packages/belos)
readonly DEBIAN_PACKAGES=(cmake ninja-build g++ make patch ca-certificates dpkg-dev
                          libeigen3-dev libhdf5-dev libgtest-dev libgmock-dev
                          libblas-dev liblapack-dev libsuitesparse-dev  # CHOLMOD (solvers/direct)
                          libopenblas0-serial  # CHOLMOD's BLAS: 1.9x faster factorizations (docs/implicit.md)
                          python3-numpy python3-matplotlib python3-h5py)  # perf/charts
readonly MPI_PACKAGES=(libopenmpi-dev openmpi-bin libmetis-dev)  # --with-mpi (docs/parallel.md)

script_dir=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
patch_dir="$script_dir/../patches"

backend=openmp
cache=${PERISHELL_CACHE:-$HOME/.cache/perishell}
jobs=$(nproc 2>/dev/null || echo 2)
prefix_file=""
use_apt=1
packages=("${DEBIAN_PACKAGES[@]}")

say() { printf 'perishell-deps: %s\n' "$*" >&2; }
die() {
  printf 'perishell-deps: error: %s\n' "$1" >&2
  [ $# -ge 2 ] && printf 'perishell-deps: how to fix: %s\n' "$2" >&2
  exit 1
}

while [ $# -gt 0 ]; do
  case "$1" in
    --backend) backend=${2:?--backend needs a value}; shift 2 ;;
    --cache) cache=${2:?--cache needs a value}; shift 2 ;;
    --jobs) jobs=${2:?--jobs needs a value}; shift 2 ;;
    --prefix-file) prefix_file=${2:?--prefix-file needs a value}; shift 2 ;;
    --no-apt) use_apt=0; shift ;;
    --with-mpi) packages+=("${MPI_PACKAGES[@]}"); shift ;;
    --patches) patch_dir=${2:?--patches needs a value}; shift 2 ;;
    -h|--help) sed -n '2,16p' "${BASH_SOURCE[0]}" | sed 's/^# \{0,1\}//'; exit 0 ;;
    *) die "unknown argument '$1'" "run with --help for the usage" ;;
  esac
done
case "$backend" in openmp|cuda) ;; *) die "unknown backend '$backend'" "use --backend openmp or --backend cuda" ;; esac
compgen -G "$patch_dir/*.patch" > /dev/null || die "no patches found in $patch_dir" "restore cmake/patches from the repository"
patch_dir=$(cd "$patch_dir" && pwd)
mkdir -p "$cache" || die "cannot create the cache directory $cache" "set PERISHELL_CACHE to a writable directory"
cache=$(cd "$cache" && pwd)

# ---------------------------------------------------------------- Debian packages
install_debian_packages() {
  local missing=() pkg
  for pkg in "${packages[@]}"; do
    dpkg-query -W -f='${Status}' "$pkg" 2>/dev/null | grep -q "install ok installed" || missing+=("$pkg")
  done
  [ ${#missing[@]} -eq 0 ] && return 0
  if [ "$use_apt" = 0 ] || [ "$(id -u)" != 0 ] || ! command -v apt-get >/dev/null; then
    die "missing Debian packages: ${missing[*]}" \
        "run as root: apt-get install -y ${missing[*]} (or rerun this script as root)"
  fi
  say "installing Debian packages: ${missing[*]}"
  DEBIAN_FRONTEND=noninteractive apt-get update -qq >&2 \
    || die "apt-get update failed" "check the machine's apt sources and network"
  DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends "${missing[@]}" > /dev/null \
    || die "apt-get install failed for: ${missing[*]}" "install them by hand and rerun"
}
if command -v dpkg-query >/dev/null; then install_debian_packages; fi

# ---------------------------------------------------------------- compilers
cxx=${CXX:-g++}
cc=${CC:-gcc}
command -v "$cxx" >/dev/null || die "C++ compiler '$cxx' not found" "apt-get install g++, or set CXX"
command -v "$cc" >/dev/null || die "C compiler '$cc' not found" "apt-get install gcc, or set CC"
cxx=$(command -v "$cxx"); cc=$(command -v "$cc")
command -v cmake >/dev/null || die "cmake not found" "apt-get install cmake"
command -v ninja >/dev/null || die "ninja not found" "apt-get install ninja-build"
host_compiler_id="$("$cxx" --version | head -n1)"
compiler_id=$host_compiler_id
if [ "$backend" = cuda ]; then
  cuda_home=${CUDA_HOME:-/usr/local/cuda}
  nvcc=$(command -v nvcc || true)
  [ -z "$nvcc" ] && [ -x "$cuda_home/bin/nvcc" ] && nvcc="$cuda_home/bin/nvcc"
  [ -n "$nvcc" ] || die "nvcc not found (needed for --backend cuda)" \
    "install the CUDA 13 toolkit and put nvcc on PATH, or set CUDA_HOME"
  export PATH="$(dirname "$nvcc"):$PATH"
  compiler_id="$compiler_id | $("$nvcc" --version | tail -n1)"
fi

# ---------------------------------------------------------------- flags
# Every flag that shapes an install lives here, so that it enters the cache key below.
kokkos_flags=(-DCMAKE_CXX_STANDARD=17 -DCMAKE_CXX_EXTENSIONS=OFF -DKokkos_ENABLE_TESTS=OFF
              -DKokkos_ENABLE_EXAMPLES=OFF -DKokkos_ENABLE_OPENMP=ON -DKokkos_ENABLE_SERIAL=OFF)
if [ "$backend" = cuda ]; then
  kokkos_flags+=(-DKokkos_ENABLE_CUDA=ON -DKokkos_ENABLE_CUDA_LAMBDA=ON -DKokkos_ARCH_HOPPER90=ON)
fi
kokkoskernels_flags=(-DCMAKE_CXX_STANDARD=17 -DCMAKE_CXX_EXTENSIONS=OFF -DKokkosKernels_ADD_DEFAULT_ETI=OFF
                     -DKokkosKernels_ENABLE_TPL_CUSPARSE=OFF -DKokkosKernels_ENABLE_TPL_CUBLAS=OFF
                     -DKokkosKernels_ENABLE_TPL_BLAS=OFF -DKokkosKernels_ENABLE_TESTS=OFF
                     -DKokkosKernels_ENABLE_EXAMPLES=OFF)
# Without ETI the templates are instantiated in perishell's own translation units.
for t in DOUBLE FLOAT COMPLEX_DOUBLE COMPLEX_FLOAT ORDINAL_INT ORDINAL_INT64_T OFFSET_INT OFFSET_SIZE_T \
         LAYOUTLEFT LAYOUTRIGHT EXECSPACE_OPENMP EXECSPACE_SERIAL EXECSPACE_THREADS EXECSPACE_CUDA \
         MEMSPACE_HOSTSPACE MEMSPACE_CUDASPACE MEMSPACE_CUDAUVMSPACE; do
  kokkoskernels_flags+=("-DKokkosKernels_INST_$t=OFF")
done
trilinos_flags=(-DCMAKE_CXX_STANDARD=17 -DBUILD_SHARED_LIBS=OFF
                -DTrilinos_ENABLE_ALL_PACKAGES=OFF -DTrilinos_ENABLE_ALL_OPTIONAL_PACKAGES=OFF
                -DTrilinos_ENABLE_Belos=ON -DTrilinos_ENABLE_Teuchos=ON
                -DTrilinos_ENABLE_Kokkos=OFF -DTrilinos_ENABLE_KokkosKernels=OFF
                -DTeuchos_ENABLE_KokkosCompat=OFF -DTeuchos_ENABLE_KokkosComm=OFF -DTPL_ENABLE_MPI=OFF
                -DTrilinos_ENABLE_TESTS=OFF -DTrilinos_ENABLE_EXAMPLES=OFF -DTrilinos_ENABLE_Fortran=OFF
                -DTrilinos_ASSERT_MISSING_PACKAGES=OFF)

# ---------------------------------------------------------------- cache keys
hash_of() { sha256sum | cut -c1-12; }
patches_key=$( (cat "$patch_dir"/*.patch; printf '%s\n' "${TRILINOS_PARTS[@]}") | hash_of)
kokkos_key=$(printf '%s\n' "$TRILINOS_DEB_VERSION" "$patches_key" "$backend" "$compiler_id" \
             "${kokkos_flags[@]}" "${kokkoskernels_flags[@]}" | hash_of)
trilinos_key=$(printf '%s\n' "$TRILINOS_DEB_VERSION" "$host_compiler_id" "${trilinos_flags[@]}" | hash_of)
src_dir="$cache/src/trilinos-$TRILINOS_DEB_VERSION-$patches_key"
kokkos_prefix="$cache/kokkos-$backend-$kokkos_key"
trilinos_prefix="$cache/teuchos-belos-$trilinos_key"
build_root="$cache/build"

write_prefix_file() {
  [ -n "$prefix_file" ] || return 0
  mkdir -p "$(dirname "$prefix_file")"
  cat > "$prefix_file.tmp" <<EOF
# Written by cmake/deps/bootstrap.sh: the dependency prefixes for backend '$backend'.
set(PERISHELL_DEPS_KOKKOS_PREFIX "$kokkos_prefix")
set(PERISHELL_DEPS_TRILINOS_PREFIX "$trilinos_prefix")
EOF
  mv "$prefix_file.tmp" "$prefix_file"
}

if [ -f "$kokkos_prefix/.perishell-complete" ] && [ -f "$trilinos_prefix/.perishell-complete" ]; then
  say "warm cache: $kokkos_prefix"
  say "warm cache: $trilinos_prefix"
  write_prefix_file
  printf '%s\n%s\n' "$kokkos_prefix" "$trilinos_prefix"
  exit 0
fi

# ---------------------------------------------------------------- source tarball
fetch_tarball() {
  local dl="$cache/downloads" tarball
  mkdir -p "$dl"
  tarball="$dl/$TRILINOS_TARBALL_NAME"
  if [ -n "${PERISHELL_TRILINOS_TARBALL:-}" ]; then
    [ -f "$PERISHELL_TRILINOS_TARBALL" ] || die "PERISHELL_TRILINOS_TARBALL=$PERISHELL_TRILINOS_TARBALL does not exist" \
      "point it at a copy of $TRILINOS_TARBALL_NAME or unset it to download through apt"
    tarball=$PERISHELL_TRILINOS_TARBALL
  elif [ ! -f "$tarball" ]; then
    # A private apt configuration: the machine's own sources with Types: deb-src; nothing system-wide changes.
    local work="$dl/apt" sources
    rm -rf "$work"; mkdir -p "$work/lists/partial" "$work/parts"
    for sources in /etc/apt/sources.list.d/*.sources; do
      [ -f "$sources" ] && sed 's/^Types: deb$/Types: deb-src/' "$sources" > "$work/parts/$(basename "$sources")"
    done
    if [ -f /etc/apt/sources.list ]; then
      sed -n 's/^deb \(.*\)$/deb-src \1/p' /etc/apt/sources.list > "$work/parts/sources.list"
    fi
    local apt_opts=(-o Dir::Etc::SourceList=/dev/null -o "Dir::Etc::SourceParts=$work/parts"
                    -o "Dir::State::Lists=$work/lists" -o Debug::NoLocking=1 -o APT::Sandbox::User=root)
    command -v apt-get >/dev/null || die "apt-get not available to fetch the Trilinos source" \
      "download $TRILINOS_TARBALL_NAME (Debian source package trilinos $TRILINOS_DEB_VERSION) and set PERISHELL_TRILINOS_TARBALL"
    say "fetching Debian source package trilinos=$TRILINOS_DEB_VERSION"
    apt-get "${apt_opts[@]}" update -qq >&2 || die "apt-get update with deb-src sources failed" \
      "check network access to the Debian mirror in /etc/apt/sources.list.d, or set PERISHELL_TRILINOS_TARBALL"
    (cd "$work" && apt-get "${apt_opts[@]}" source --download-only "trilinos=$TRILINOS_DEB_VERSION" >&2) \
      || die "could not download source package trilinos=$TRILINOS_DEB_VERSION" \
             "the mirror must serve bookworm sources; or download $TRILINOS_TARBALL_NAME and set PERISHELL_TRILINOS_TARBALL"
    mv "$work/$TRILINOS_TARBALL_NAME" "$tarball.part" && mv "$tarball.part" "$tarball"
    rm -rf "$work"
  fi
  local actual
  actual=$(sha256sum "$tarball" | cut -d' ' -f1)
  if [ "$actual" != "$TRILINOS_TARBALL_SHA256" ]; then
    die "checksum mismatch for $tarball: expected sha256 $TRILINOS_TARBALL_SHA256, got $actual" \
        "delete $tarball and rerun to download it again (or fix PERISHELL_TRILINOS_TARBALL)"
  fi
  printf '%s\n' "$tarball"
}

extract_and_patch() {
  [ -f "$src_dir/.perishell-patched" ] && return 0
  local tarball tmp top_files part parts=() p
  tarball=$(fetch_tarball)
  tmp="$src_dir.tmp.$$"
  rm -rf "$tmp" "$src_dir"; mkdir -p "$tmp"
  say "extracting Kokkos, Kokkos Kernels, Teuchos, Belos and the TriBITS build files"
  mapfile -t top_files < <(tar tzf "$tarball" | awk -F/ 'NF == 2 && $2 != ""')
  for part in "${TRILINOS_PARTS[@]}"; do parts+=("$TRILINOS_TOP/$part/*"); done
  tar xzf "$tarball" -C "$tmp" --strip-components=1 --wildcards "${top_files[@]}" "${parts[@]}" \
      || { rm -rf "$tmp"; die "extracting $tarball failed" "delete it and rerun"; }
  for p in "$patch_dir"/*.patch; do
    say "applying $(basename "$p")"
    (cd "$tmp" && patch -p1 --forward --batch --quiet < "$p" >&2) \
      || { rm -rf "$tmp"; die "patch $(basename "$p") failed to apply to Trilinos $TRILINOS_DEB_VERSION" \
             "the patches in cmake/patches/ are written for Kokkos 3.4.01 from trilinos $TRILINOS_DEB_VERSION; check the tarball and the patch"; }
  done
  touch "$tmp/.perishell-patched"
  mkdir -p "$(dirname "$src_dir")"
  mv "$tmp" "$src_dir"
}

cmake_build_install() {  # name source_dir build_dir [cmake args...]
  local name=$1 src=$2 build=$3; shift 3
  say "configuring $name"
  rm -rf "$build"; mkdir -p "$build_root"
  cmake -S "$src" -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=Release "$@" > "$build.configure.log" 2>&1 \
    || { tail -n 40 "$build.configure.log" >&2; die "configuring $name failed (log: $build.configure.log)" \
          "read the log; a missing compiler or Debian package is the usual cause"; }
  say "building $name with $jobs jobs"
  cmake --build "$build" --parallel "$jobs" > "$build.build.log" 2>&1 \
    || { tail -n 40 "$build.build.log" >&2; die "building $name failed (log: $build.build.log)" \
          "read the log; delete $cache to start from scratch"; }
  cmake --install "$build" > "$build.install.log" 2>&1 \
    || die "installing $name failed (log: $build.install.log)" "check that the cache directory is writable"
}

build_kokkos_stack() {
  [ -f "$kokkos_prefix/.perishell-complete" ] && return 0
  rm -rf "$kokkos_prefix"
  local compiler_args=(-DCMAKE_CXX_COMPILER="$cxx")
  if [ "$backend" = cuda ]; then
    compiler_args=(-DCMAKE_CXX_COMPILER="$src_dir/packages/kokkos/bin/nvcc_wrapper")
    export NVCC_WRAPPER_DEFAULT_COMPILER="$cxx"
  fi
  cmake_build_install "Kokkos ($backend)" "$src_dir/packages/kokkos" "$build_root/kokkos-$backend" \
    "${compiler_args[@]}" "${kokkos_flags[@]}" -DCMAKE_INSTALL_PREFIX="$kokkos_prefix"
  if [ "$backend" = cuda ]; then compiler_args=(-DCMAKE_CXX_COMPILER="$kokkos_prefix/bin/nvcc_wrapper"); fi
  cmake_build_install "Kokkos Kernels ($backend)" "$src_dir/packages/kokkos-kernels" "$build_root/kokkoskernels-$backend" \
    "${compiler_args[@]}" "${kokkoskernels_flags[@]}" \
    -DCMAKE_INSTALL_PREFIX="$kokkos_prefix" -DKokkos_ROOT="$kokkos_prefix"
  touch "$kokkos_prefix/.perishell-complete"
  rm -rf "$build_root/kokkos-$backend" "$build_root/kokkoskernels-$backend"
}

build_teuchos_belos() {
  [ -f "$trilinos_prefix/.perishell-complete" ] && return 0
  rm -rf "$trilinos_prefix"
  cmake_build_install "Teuchos + Belos (host)" "$src_dir" "$build_root/teuchos-belos" \
    -DCMAKE_CXX_COMPILER="$cxx" -DCMAKE_C_COMPILER="$cc" "${trilinos_flags[@]}" \
    -DCMAKE_INSTALL_PREFIX="$trilinos_prefix"
  touch "$trilinos_prefix/.perishell-complete"
  rm -rf "$build_root/teuchos-belos"
}

extract_and_patch
build_kokkos_stack
build_teuchos_belos
write_prefix_file
say "ready: $kokkos_prefix"
say "ready: $trilinos_prefix"
printf '%s\n%s\n' "$kokkos_prefix" "$trilinos_prefix"
