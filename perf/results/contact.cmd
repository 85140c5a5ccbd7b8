build/openmp/perf/bench_contact 80 12 200
