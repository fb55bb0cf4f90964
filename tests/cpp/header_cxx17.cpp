// pelage.h compiles as strict C++17 (-std=c++17 -Wall -Wextra -Werror
// -pedantic), survives being included twice, and declares its functions with
// C linkage (this file links against the Rust static library).
#include <pelage.h>
#include <pelage.h>  // twice on purpose: the include guard must hold

#include <cstdio>
#include <type_traits>

static_assert(std::is_trivially_copyable_v<PelageRoot> && std::is_standard_layout_v<PelageRoot>);
static_assert(std::is_trivially_copyable_v<PelageStampParams> && std::is_standard_layout_v<PelageStampParams>);
static_assert(std::is_trivially_copyable_v<PelageMeshDesc> && std::is_standard_layout_v<PelageMeshDesc>);
static_assert(sizeof(PelageRoot) == 20);
static_assert(std::is_same_v<decltype(pelage_version()), uint32_t>);

int main() {
  const PelageStampParams params = pelage_stamp_params_defaults();
  const uint32_t header = PELAGE_VERSION_MAJOR * 10000 + PELAGE_VERSION_MINOR * 100 + PELAGE_VERSION_PATCH;
  std::printf("C++ sees pelage %u (header %u); default black_scale %.2f\n", pelage_version(), header,
              double(params.black_scale));
  return pelage_version() == header ? 0 : 1;
}
