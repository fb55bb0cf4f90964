/* pelage.h compiles as strict C99 (-std=c99 -Wall -Wextra -Werror -pedantic),
 * survives being included twice, and its version macros match the library. */
#include <pelage.h>
#include <pelage.h> /* twice on purpose: the include guard must hold */

#include <stddef.h>
#include <stdio.h>

/* Root records are stored and exchanged as raw bytes: pin their C layout. */
typedef char pelage_root_is_20_bytes[sizeof(PelageRoot) == 20 ? 1 : -1];
typedef char pelage_root_rank_at_16[offsetof(PelageRoot, rank) == 16 ? 1 : -1];
typedef char pelage_status_ok_is_0[PELAGE_STATUS_OK == 0 ? 1 : -1];

int main(void) {
  const unsigned long header = PELAGE_VERSION_MAJOR * 10000ul + PELAGE_VERSION_MINOR * 100ul + PELAGE_VERSION_PATCH;
  const unsigned long library = (unsigned long)pelage_version();
  printf("header %d.%d.%d (%lu), library %lu\n", PELAGE_VERSION_MAJOR, PELAGE_VERSION_MINOR,
         PELAGE_VERSION_PATCH, header, library);
  if (header != library) {
    fprintf(stderr, "version mismatch: header %lu, library %lu\n", header, library);
    return 1;
  }
  return 0;
}
