/* A submission built for K = 4 sub-steps per time unit, as the 2019 authors' parallel-2 is: K is
 * compiled in, the arguments are ignored. The simulation is plain_allpairs.c, which the tests copy
 * beside it; psim check must judge its output at K = 4. */
#define main plain_allpairs_main
#include "plain_allpairs.c"
#undef main

int main(int argc, char** argv) {
  char* built_for[] = {argv[0], "4", NULL};
  (void)argc;
  return plain_allpairs_main(2, built_for);
}
