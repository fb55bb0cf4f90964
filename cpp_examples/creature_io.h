// Helpers shared by the creature demo and the C++ tests: OBJ and PNG I/O,
// a checked pelage stamping call, straight/combed strand growth into
// Embree-ready buffers, and an Embree device that records its errors.
#pragma once

#include <embree3/rtcore.h>
#include <pelage.h>

#include <chrono>
#include <cstddef>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <vector>

namespace creature {

// pelage's PelageStatus as an exception: "what: status string: last error".
struct PelageError : std::runtime_error {
  PelageStatus status;
  PelageError(PelageStatus s, const std::string& what);
};

// Throws PelageError unless `status` is PELAGE_STATUS_OK.
void check(PelageStatus status, const char* what);

// An indexed triangle mesh with per-vertex attributes, packed (stride 12/8).
struct Mesh {
  std::vector<float> positions;   // x, y, z per vertex
  std::vector<float> normals;     // x, y, z per vertex (empty if the OBJ has none)
  std::vector<float> uvs;         // u, v per vertex (empty if the OBJ has none)
  std::vector<uint32_t> indices;  // three per triangle

  size_t vertex_count() const { return positions.size() / 3; }
  size_t triangle_count() const { return indices.size() / 3; }
  // A view for pelage calls; borrows this mesh's storage.
  PelageMeshDesc desc() const;
  // Area of triangle `t`.
  double area(size_t t) const;
  // Texture coordinates at barycentric (u, v) on triangle `t` (pelage's convention).
  void uv_at(size_t t, float u, float v, float out[2]) const;
};

// Reads a Wavefront OBJ (tinyobjloader), triangulating polygons. OBJ corners
// index positions, UVs and normals separately; pelage needs per-vertex
// attributes, so every distinct (v, vt, vn) triple becomes one vertex
// (positions are duplicated along UV seams). Throws std::runtime_error.
Mesh load_obj(const std::string& path);

// An 8-bit grayscale image; row 0 is v = 0 (pelage's texture convention:
// texel (x, y) covers uv ((x + .5) / w, (y + .5) / h)).
struct GrayImage {
  int width = 0;
  int height = 0;
  std::vector<uint8_t> texels;

  uint8_t at(int x, int y) const { return texels[size_t(y) * size_t(width) + size_t(x)]; }
  // Nearest texel to uv (clamped), 0..255.
  uint8_t nearest(float u, float v) const;
  // Bilinear lookup in [0, 1], clamped at the edges, as pelage samples textures.
  float bilinear(float u, float v) const;
  // This image as a pelage texture map (borrows the texels).
  PelageMap map() const;
};

// Reads a PNG as 8-bit gray (libpng; colour images are converted). Throws.
GrayImage load_png_gray(const std::string& path);
// Writes 8-bit RGB pixels, row 0 on top. Throws.
void write_png_rgb(const std::string& path, int width, int height, const std::vector<uint8_t>& rgb);

// Query, allocate and stamp: the roots pelage places on `mesh`. Throws.
std::vector<PelageRoot> stamp(const Mesh& mesh, const PelageStampParams& params, PelageStampInfo* info = nullptr);

// Positions and unit normals (float3, packed) of `roots` on `mesh`. Throws.
void evaluate(const Mesh& mesh, const std::vector<PelageRoot>& roots, std::vector<float>& positions,
              std::vector<float>& normals);

// How strands grow from their roots.
struct StrandParams {
  float length = 0.06f;
  float root_radius = 0.0015f;
  float tip_radius = 0.0015f;
  float tilt_root_deg = 60.0f;          // angle from the normal at the root
  float tilt_tip_deg = 60.0f;           // ... and at the tip (equal: straight strands)
  float comb[3] = {0.0f, -1.0f, 0.0f};  // world direction the fur is combed toward
};

// Embree-ready curves: float4 (x, y, z, radius) control points, stride 16,
// four per strand, and one uint32 per strand pointing at its first control
// point, for RTC_GEOMETRY_TYPE_ROUND_CATMULL_ROM_CURVE. A uniform Catmull-Rom
// segment runs from control point 1 (the root) to 2 (the tip); 0 and 3 are
// phantom points that set the end tangents.
struct Strands {
  std::vector<float> control_points;
  std::vector<uint32_t> indices;
  size_t count() const { return indices.size(); }
};

// One strand per root (`positions`/`normals` float3, packed): it leaves the
// skin tilted `tilt_root_deg` from the normal toward the comb direction
// (projected onto the tangent plane), bending to `tilt_tip_deg` at the tip.
Strands grow_strands(const std::vector<float>& positions, const std::vector<float>& normals,
                     const StrandParams& params);

// Control points that are not finite or have a negative radius (Embree drops
// such primitives silently, so hosts must check them).
size_t count_bad_control_points(const Strands& strands);

// An Embree device whose error callback records every error.
struct Device {
  RTCDevice device = nullptr;
  std::vector<std::string> errors;
  explicit Device(const char* config = nullptr);
  ~Device();
  Device(const Device&) = delete;
  Device& operator=(const Device&) = delete;
  // Throws if the callback fired or rtcGetDeviceError is not RTC_ERROR_NONE.
  void check(const char* what);
};

// Adds `mesh` to `scene` as a triangle geometry sharing the mesh's buffers.
unsigned attach_mesh(RTCDevice device, RTCScene scene, const Mesh& mesh);
// Adds `strands` to `scene` as round Catmull-Rom curves sharing its buffers.
unsigned attach_strands(RTCDevice device, RTCScene scene, const Strands& strands);

// Seconds since construction.
struct Stopwatch {
  std::chrono::steady_clock::time_point start = std::chrono::steady_clock::now();
  double seconds() const {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  }
};

}  // namespace creature
