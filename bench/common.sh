# Sourced by the benchmark scripts (bench/run.sh, bench/lod/run.sh,
# bench/lod/sweep.sh); needs $repo set.

# libgomp spins at barriers by default. On a shared 2-core machine another
# process then slows OpenMP code several-fold (Open3D's Poisson at depth 8:
# 5 s -> 42 s beside one compile), so the times would measure the neighbours.
# Passive waiting keeps them about the work; the reports say which policy ran.
# OMP_WAIT_POLICY=active <script> ... measures libgomp's default instead.
export OMP_WAIT_POLICY="${OMP_WAIT_POLICY:-passive}"

# bench_binary SCRIPT BUILD TARGET: sets $binary to BUILD/bin/TARGET, or says
# how to build it and exits (the scripts build nothing themselves).
bench_binary() {
  binary="$2/bin/$3"
  if [[ ! -x "$binary" ]]; then
    echo "$1: no benchmark binary at $binary" >&2
    echo "  build it first: cmake -S $repo -B $2 -DCMAKE_BUILD_TYPE=Release &&" \
         "make -C $2 $3" >&2
    exit 1
  fi
}
