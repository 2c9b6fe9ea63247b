/* A pthreads submission that pins its own threads, as courses get them: T from argv[1], thread i
 * pinned with pthread_setaffinity_np to the i-th CPU it was started on (the next one round, as
 * such programs do when T exceeds them), checked, then the simulation (plain_allpairs.c, which the
 * tests copy beside it) at K = 1. A binding that fails or lands elsewhere stops it. */
#define _GNU_SOURCE
#include <pthread.h>
#include <sched.h>
#include <stdio.h>

#define main plain_allpairs_main
#include "plain_allpairs.c"
#undef main

static cpu_set_t start;

static void* pin_self(void* arg) {
  const long index = (long)arg;
  int cpus[CPU_SETSIZE], n = 0;
  for (int cpu = 0; cpu < CPU_SETSIZE; ++cpu)
    if (CPU_ISSET(cpu, &start)) cpus[n++] = cpu;
  cpu_set_t one, have;
  CPU_ZERO(&one);
  CPU_SET(cpus[index % n], &one);
  if (pthread_setaffinity_np(pthread_self(), sizeof one, &one) != 0 ||
      pthread_getaffinity_np(pthread_self(), sizeof have, &have) != 0 || !CPU_EQUAL(&one, &have))
    return (void*)1;
  return NULL;
}

int main(int argc, char** argv) {
  const int threads = argc > 1 ? atoi(argv[1]) : 0;
  if (threads < 1) {
    fprintf(stderr, "usage: pthreads_pin T < scene\n");
    return 2;
  }
  sched_getaffinity(0, sizeof start, &start);
  pthread_t team[64];
  int failed = 0;
  for (long i = 0; i < threads && i < 64; ++i) pthread_create(&team[i], NULL, pin_self, (void*)i);
  for (long i = 0; i < threads && i < 64; ++i) {
    void* result;
    pthread_join(team[i], &result);
    failed += result != NULL;
  }
  if (failed) {
    fprintf(stderr, "pthreads_pin: %d of %d threads could not pin themselves\n", failed, threads);
    return 3;
  }
  char* plain[] = {argv[0], NULL};
  return plain_allpairs_main(1, plain);
}
