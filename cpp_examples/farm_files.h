// The files a shot writes on a farm, made safe to kill, requeue and rerun
// (issue 50): every file is written whole or not at all (a temporary file in
// the same folder, flushed to disk, renamed into place), and every file the
// farm reads is sealed with the shot's identity, its frame and its sample,
// so a reader refuses a file from another frame or shot, a truncated one and
// one written before files carried their place. docs/FORMAT.md has the layouts.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace farm {

// Which shot a file belongs to: a hash of everything its bits depend on (the
// creature's bytes, the hair and frame counts, the tool's settings and the
// pelage version), and the shot's frame count.
struct Identity {
  uint64_t shot = 0;
  uint32_t frames = 0;
  bool operator==(const Identity& o) const { return shot == o.shot && frames == o.frames; }
};

// What a sealed file holds (the seal's first header field; never reused).
enum class Kind : uint64_t { Groom = 1, GuideCache = 2, Mesh = 3, TrimRecords = 4, TrimLengths = 5, SimState = 6 };

// The frame or sample field of a file that holds no single one (the shot's
// files; a frame's files that hold every shutter sample).
constexpr uint32_t kEvery = UINT32_MAX;

// 64-bit FNV-1a of `size` bytes, continuing from `hash`.
uint64_t fnv1a(const void* data, size_t size, uint64_t hash = 0xcbf29ce484222325ull);

// The framing of pelage's files (docs/FORMAT.md, "Framing"): `magic` (8
// bytes), `version`, the header `fields`, then `payload` under a CRC-32.
std::vector<unsigned char> frame_bytes(const char* magic, uint32_t version, const std::vector<uint64_t>& fields,
                                       const unsigned char* payload, size_t size);

// A framed file's header fields and payload (a view into the bytes).
struct Framed {
  std::vector<uint64_t> fields;
  const unsigned char* payload = nullptr;
  size_t size = 0;
};
// Checks framing written by frame_bytes: magic, version, field count, length
// and CRC. Throws std::runtime_error naming `path` and what is wrong.
Framed unframe(const std::string& path, const std::vector<unsigned char>& bytes, const char* magic, uint32_t version,
               size_t field_count);

// `size` bytes of `file` sealed for frame `frame`, sample `sample` of shot `id`.
std::vector<unsigned char> seal(const Identity& id, Kind kind, uint32_t frame, uint32_t sample,
                                const unsigned char* file, size_t size);

// The file at `path`, unsealed: its identity and the bytes it seals. Throws
// when it cannot be read, is not sealed (an old file, or not the farm's),
// is corrupt, or holds another kind of file.
struct Sealed {
  Identity id;
  uint32_t frame = kEvery, sample = kEvery;
  std::vector<unsigned char> file;
};
Sealed unseal(const std::string& path, Kind kind);

// The bytes sealed at `path`, refused (thrown, with a message that says
// where the file belongs) unless it is frame `frame`, sample `sample` of shot `id`.
std::vector<unsigned char> read_sealed(const std::string& path, const Identity& id, Kind kind, uint32_t frame,
                                       uint32_t sample);

// Whether `path` holds a good sealed file for that place: what a rerun skips.
bool sealed_ok(const std::string& path, const Identity& id, Kind kind, uint32_t frame, uint32_t sample);

// Writes `size` bytes to `path` whole or not at all: into `path.part-XXXXXX`
// in the same folder, fsync, rename over `path`, fsync the folder. On any
// error (a full disk) the temporary file is removed and std::runtime_error
// thrown; a SIGTERM/SIGINT/SIGHUP (scancel) removes it too (install_signal_cleanup).
// Removes first the temporary files an earlier, killed writer of `path` left.
void write_atomic(const std::string& path, const unsigned char* data, size_t size);

// Makes SIGTERM, SIGINT and SIGHUP remove the temporary file being written
// before the process dies of the signal. Call once, before any write_atomic.
void install_signal_cleanup();

// 8-bit RGB pixels as a PNG whose tEXt chunk "pelage-shot" names the shot
// and the frame (`shot=<16 hex digits> frames=<n> frame=<f>`).
std::vector<unsigned char> png_rgb(int width, int height, const std::vector<uint8_t>& rgb, const Identity& id,
                                   uint32_t frame);

// Whether `path` is a whole PNG (every chunk's CRC, IEND last) with the
// tEXt chunk png_rgb writes for `frame` of shot `id`.
bool png_ok(const std::string& path, const Identity& id, uint32_t frame);

}  // namespace farm
