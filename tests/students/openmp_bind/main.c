/* An OpenMP submission as a parallel-computing course gets them: its threads bound with
 * proc_bind(close) over OMP_PLACES, T from OMP_NUM_THREADS, built by its Makefile. Before the
 * simulation (plain_allpairs.c, which the tests copy beside it) it checks that the runtime's
 * binding holds: each thread on exactly its place's CPUs. libgomp binds each thread with
 * sched_setaffinity (the first before main); where that call fails, thread creation fails and the
 * program stops (issue 56). */
#define _GNU_SOURCE
#include <omp.h>
#include <sched.h>
#include <stdio.h>

#define main plain_allpairs_main
#include "plain_allpairs.c"
#undef main

/* The threads not bound as OMP_PLACES and proc_bind(close) ask. */
static int wrongly_bound(void) {
  int wrong = 0;
#pragma omp parallel proc_bind(close) reduction(+ : wrong)
  {
    const int place = omp_get_place_num();
    const int n = place < 0 ? 0 : omp_get_place_num_procs(place);
    int ids[CPU_SETSIZE];
    cpu_set_t want, have;
    CPU_ZERO(&want);
    if (n > 0) omp_get_place_proc_ids(place, ids);
    for (int i = 0; i < n; ++i) CPU_SET(ids[i], &want);
    if (n == 0 || sched_getaffinity(0, sizeof have, &have) != 0 || !CPU_EQUAL(&want, &have))
      ++wrong;
  }
  return wrong;
}

int main(int argc, char** argv) {
  const int wrong = wrongly_bound();
  if (wrong) {
    fprintf(stderr, "openmp_bind: %d of %d threads not bound as OMP_PLACES=%s asks\n", wrong,
            omp_get_max_threads(), getenv("OMP_PLACES") ? getenv("OMP_PLACES") : "(unset)");
    return 3;
  }
  char* plain[] = {argv[0], NULL}; /* K = 1, whatever its arguments */
  (void)argc;
  return plain_allpairs_main(1, plain);
}
