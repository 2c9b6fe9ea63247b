/* A submission built for K = 4 sub-steps that counts its own sub-steps, as the 2019 authors'
 * parallel-2 does: every sub-step printed in print mode, numbered 0 to S x K, each velocity what
 * the particle moves in one sub-step (v / K). The simulation is plain_allpairs.c, which the tests
 * copy beside it; psim check must judge it with --sub-steps-numbered at K = 4. */
#define PRINTS_SUB_STEPS
#define main plain_allpairs_main
#include "plain_allpairs.c"
#undef main

int main(int argc, char** argv) {
  char* built_for[] = {argv[0], "4", NULL};
  (void)argc;
  return plain_allpairs_main(2, built_for);
}
