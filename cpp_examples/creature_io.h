// Helpers shared by the creature demo and the C++ tests: OBJ and PNG I/O,
// checked pelage calls (stamp, bind, groom, expand), combed guides, straight
// strand growth into Embree-ready buffers, an Embree device that records its
// errors, and the skin-coverage measurement (stamped vs. random roots).
#pragma once

#include <embree3/rtcore.h>
#include <pelage.h>

#include <chrono>
#include <cmath>
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

// A small float3 for hosts' geometry code (found by ADL).
struct V3 {
  float x = 0, y = 0, z = 0;
};
inline V3 operator+(V3 a, V3 b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
inline V3 operator-(V3 a, V3 b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
inline V3 operator*(float s, V3 a) { return {s * a.x, s * a.y, s * a.z}; }
inline float dot(V3 a, V3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
inline V3 cross(V3 a, V3 b) { return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x}; }
inline float length(V3 a) { return std::sqrt(dot(a, a)); }
inline V3 normalize(V3 a) { return (1.0f / length(a)) * a; }
// Element `i` of a packed float3 array.
inline V3 at3(const std::vector<float>& v, size_t i) { return {v[3 * i], v[3 * i + 1], v[3 * i + 2]}; }

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
// The same for `count` float4 (x, y, z, radius) points, packed.
size_t count_bad_points(const float* float4, size_t count);

// --- Guide interpolation ---------------------------------------------------

// Guides combed like `combed_guides` in tests/src/measure.rs: `cvs` points per
// root, `length / (cvs - 1)` apart, leaving along the normal n and turning
// toward world -y projected on the tangent plane (comb): the step at
// t = j / (cvs - 1) goes along normalize(n (1 - 0.6 t) + comb 0.6 t). float3, packed.
std::vector<float> combed_guides(const Mesh& mesh, const std::vector<PelageRoot>& roots, uint32_t cvs, float length);

// `roots.size()` guides of `cvs` packed float3 points each; borrows both vectors.
PelageGuidesDesc guides_desc(const std::vector<PelageRoot>& roots, const std::vector<float>& points, uint32_t cvs);

// Query, allocate and bind `count` strands to `guides` on the rest pose. Throws.
std::vector<PelageStrandBinding> bind(const Mesh& mesh, const PelageGuidesDesc& guides, const PelageRoot* strands,
                                      size_t count, const PelageBindParams& params, PelageBindInfo* info = nullptr);

// Groom values of `count` roots sampled from `maps`. Throws.
std::vector<PelageStrandGroom> groom(const Mesh& mesh, const PelageGroomMaps& maps, const PelageRoot* roots,
                                     size_t count);

// A whole file's bytes; throws when it cannot be read.
std::vector<unsigned char> read_file(const std::string& path);

// Writes `size` bytes to `path`; throws when it cannot be written.
void write_file(const std::string& path, const unsigned char* data, size_t size);

// The groom file of `hairs` render hairs stamped on `rest` (seed 2) and
// stored patch by patch (runs of `patch_size`, pelage_patch_plan), bound to
// the guides `guide_roots` / `rest_points` (`cvs` points each) and groomed
// short, kinked and clumped: what the render-time examples write once per
// asset. Throws.
std::vector<unsigned char> groom_file(const Mesh& rest, const std::vector<PelageRoot>& guide_roots,
                                      const std::vector<float>& rest_points, uint32_t cvs, uint32_t hairs,
                                      uint32_t patch_size);

// Settles `count` groomed strands out of the body at the rest pose
// (pelage_settle, all cores): `grooms` updated in place. Throws.
PelageSettleInfo settle(const Mesh& rest, const PelageGuidesDesc& rest_guides, const PelageRoot* strands,
                        const PelageStrandBinding* bindings, PelageStrandGroom* grooms, size_t count,
                        const PelageExpandParams& params);

// A groom's strands checked and copied once (pelage_groom_new), released
// with pelage_groom_free. Throws on bad records.
class Groom {
 public:
  Groom(const PelageRoot* strands, const PelageStrandBinding* bindings, const PelageStrandGroom* grooms,
        size_t count);
  ~Groom() { pelage_groom_free(groom_); }
  Groom(const Groom&) = delete;
  Groom& operator=(const Groom&) = delete;
  PelageGroom get() const { return groom_; }

 private:
  PelageGroom groom_ = nullptr;
};

// One frame (pelage_frame_new, pelage_frame_set_guides): the deformed mesh
// copied and checked, its tangents, and the posed guides, prepared once for
// every expansion of the frame. Throws.
class Frame {
 public:
  Frame(const Mesh& mesh, const PelageGuidesDesc& guides, const PelageExpandParams& params);
  ~Frame() { pelage_frame_free(frame_); }
  Frame(const Frame&) = delete;
  Frame& operator=(const Frame&) = delete;
  PelageFrame get() const { return frame_; }

 private:
  PelageFrame frame_ = nullptr;
};

// Expansion parameters and the curves they write.
class Expander {
 public:
  explicit Expander(const PelageExpandParams& params);
  // float4 points written per curve (points_per_strand, + 2 when pinned).
  size_t points_per_curve() const { return per_curve_; }
  const PelageExpandParams& params() const { return params_; }
  // Writes the curves of strands[0..count) (bindings and grooms parallel)
  // into `points`: float4, stride 16, `capacity` points (pelage_expand:
  // the records are checked). Throws.
  void expand(const Frame& frame, const PelageRoot* strands, const PelageStrandBinding* bindings,
              const PelageStrandGroom* grooms, size_t count, float* points, size_t capacity,
              uint32_t* curve_counts = nullptr, uint32_t* curve_ids = nullptr);
  // The same for the strands first..first + count of `groom`
  // (pelage_groom_expand: the records are not checked again).
  void expand(const Frame& frame, const Groom& groom, size_t first, size_t count, float* points, size_t capacity);

 private:
  PelageExpandParams params_;
  size_t per_curve_ = 0;
};

// Embree's index buffer for `curves` curves of `per_curve` points stored back
// to back (pelage_curves_segment_indices). Throws.
std::vector<uint32_t> segment_indices(size_t curves, size_t per_curve);

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
// Adds round Catmull-Rom curves sharing the host's buffers: `point_count`
// float4 points (stride 16) and `segment_count` uint32 indices, each the
// first of a segment's 4 control points. Several geometries may share one
// point buffer with different index buffers (a level of detail).
unsigned attach_curves(RTCDevice device, RTCScene scene, const float* points, size_t point_count,
                       const uint32_t* indices, size_t segment_count);

// --- Skin coverage: stamped vs. uniformly random roots -----------------------

// splitmix64: a small deterministic generator for random baselines.
struct Rng {
  uint64_t state;
  uint64_t next() {
    uint64_t z = (state += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
  }
  float unit() { return float(next() >> 40) * (1.0f / 16777216.0f); }
};

// Per-triangle cumulative weights for random roots with the same expected
// density as pelage's stamp: the density is sampled at the centroid,
// triangles below bald_below get nothing, and a triangle scaled by s takes s^2
// as many roots.
std::vector<double> random_root_cdf(const Mesh& mesh, const GrayImage& density, const PelageStampParams& params);
// `count` uniformly random roots drawn from `cdf`; id = rank = index.
std::vector<PelageRoot> random_roots(const std::vector<double>& cdf, size_t count, uint64_t seed);

// First hit of a ray, or geomID == RTC_INVALID_GEOMETRY_ID.
RTCRayHit trace(RTCScene scene, V3 org, V3 dir, float tfar = 1e30f);

// Orthographic views of `resolution`^2 parallel rays around the mesh;
// measures how much furred skin a set of strands leaves visible.
struct Coverage {
  struct View {
    const char* name;
    V3 forward;
  };
  const Mesh& mesh;
  const GrayImage& density;
  std::vector<View> views;
  int resolution;
  V3 center;                    // of the mesh's bounding box
  float half;                   // half the side of the square each view covers
  std::vector<uint8_t> furred;  // per ray: hits skin with density > 0 in the skin-only scene
  size_t furred_rays = 0;
  static constexpr int tile = 16;

  // The four side views (front, right, back, left), framing the mesh's
  // bounding box with a 10 % margin.
  Coverage(const Mesh& mesh, const GrayImage& density, int resolution);
  void ray(size_t view, int x, int y, V3& org, V3& dir) const;
  size_t rays_per_view() const { return size_t(resolution) * size_t(resolution); }
  // Marks the rays that see furred skin when there is no fur.
  void prepare(RTCScene skin_only);

  // What one set of strands leaves visible.
  // Tiles are tile x tile rays of one view, all on furred skin.
  struct Seen {
    double skin;     // fraction of the furred-skin rays whose first hit is the skin
    double worst;    // 99th percentile over tiles of the fraction of a tile's rays that see skin
    double patches;  // fraction of tiles where >= 25 % of the rays see skin
    size_t tiles;    // tiles measured
  };
  Seen skin_visible(RTCScene scene, unsigned skin_id) const;
};

// Seconds since construction.
struct Stopwatch {
  std::chrono::steady_clock::time_point start = std::chrono::steady_clock::now();
  double seconds() const {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  }
};

}  // namespace creature
