/* Deliberately broken: proves UBSan is on in the sanitizer build.
 * CTest expects UBSan's "runtime error" report. */
#include <limits.h>
#include <stdio.h>

int main(int argc, char **argv) {
  (void)argv;
  volatile int big = INT_MAX - 1 + argc; /* INT_MAX, not known at compile time */
  int overflow = big + 1;                /* signed integer overflow */
  printf("%d\n", overflow);
  return 0;
}
