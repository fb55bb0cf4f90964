/* Deliberately broken: proves the sanitizer build really is instrumented.
 * Built with the same flags as c_contract_asan; CTest expects ASan's report
 * (a use after free, which only ASan can see). */
#include <stdio.h>
#include <stdlib.h>

int main(int argc, char **argv) {
  (void)argv;
  volatile int index = argc; /* 1, not known at compile time */
  int *p = malloc(8 * sizeof *p);
  if (!p) return 2;
  for (int i = 0; i < 8; ++i) p[i] = i;
  free(p);
  printf("reading p[%d] after free\n", index);
  return p[index] == 12345 ? 3 : 0; /* heap-use-after-free */
}
