#include "farm_files.h"

#include <dirent.h>
#include <fcntl.h>
#include <png.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <iterator>
#include <stdexcept>

namespace farm {

namespace {

// CRC-32 (IEEE 802.3, as zlib and pelage's files).
uint32_t crc32(const unsigned char* data, size_t size, uint32_t crc = 0) {
  static const auto table = [] {
    std::vector<uint32_t> t(256);
    for (uint32_t i = 0; i < 256; ++i) {
      uint32_t c = i;
      for (int k = 0; k < 8; ++k) c = (c & 1) ? 0xEDB88320u ^ (c >> 1) : c >> 1;
      t[i] = c;
    }
    return t;
  }();
  crc = ~crc;
  for (size_t i = 0; i < size; ++i) crc = table[(crc ^ data[i]) & 0xFF] ^ (crc >> 8);
  return ~crc;
}

void put32(std::vector<unsigned char>& out, uint32_t v) {
  for (int i = 0; i < 4; ++i) out.push_back(uint8_t(v >> (8 * i)));
}
void put64(std::vector<unsigned char>& out, uint64_t v) {
  for (int i = 0; i < 8; ++i) out.push_back(uint8_t(v >> (8 * i)));
}
uint64_t get(const unsigned char* p, int bytes) {
  uint64_t v = 0;
  for (int i = bytes - 1; i >= 0; --i) v = v << 8 | p[i];
  return v;
}
uint32_t get_be32(const unsigned char* p) {
  return uint32_t(p[0]) << 24 | uint32_t(p[1]) << 16 | uint32_t(p[2]) << 8 | p[3];
}

std::vector<unsigned char> read_all(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::runtime_error("cannot read " + path + ": " + std::strerror(errno));
  return {std::istreambuf_iterator<char>(in), {}};
}

const char kSealMagic[] = "PLSHOT\0";  // 8 bytes with the terminator
const uint32_t kSealVersion = 1;
const size_t kSealFields = 5;
const char* const kKindNames[] = {"",          "groom file",        "guide cache",      "deformed mesh file",
                                  "trim records file", "trim lengths file", "simulation state"};

const char* kind_name(uint64_t kind) { return kind >= 1 && kind <= 6 ? kKindNames[kind] : "file of an unknown kind"; }

std::string hex(uint64_t v) {
  char s[17];
  std::snprintf(s, sizeof s, "%016llx", static_cast<unsigned long long>(v));
  return s;
}

std::string place(uint32_t frame, uint32_t sample) {
  std::string s = frame == kEvery ? "the whole shot" : "frame " + std::to_string(frame);
  if (sample != kEvery) s += " sample " + std::to_string(sample);
  return s;
}

// The temporary file being written, for the signal handler: a fixed buffer
// (a handler may not allocate), valid while `temp_set` is 1.
char temp_path[4096];
volatile std::sig_atomic_t temp_set = 0;

extern "C" void remove_temp_and_die(int sig) {
  if (temp_set) unlink(temp_path);
  std::signal(sig, SIG_DFL);
  std::raise(sig);
}

std::string errno_text() { return std::strerror(errno); }

// Removes `dir/base.part-*`: the temporary files of a writer of `base` that
// was killed (SIGKILL leaves them). Only one task writes a given path at a
// time, so none of them is being written now.
void remove_stale_temps(const std::string& dir, const std::string& base) {
  DIR* d = opendir(dir.c_str());
  if (!d) return;
  const std::string prefix = base + ".part-";
  while (const dirent* e = readdir(d)) {
    if (std::strncmp(e->d_name, prefix.c_str(), prefix.size()) == 0) unlink((dir + "/" + e->d_name).c_str());
  }
  closedir(d);
}

// The fault test's hook: SHOT_FAULT_STALL=<entry>[,<entry>...] makes the
// writer of a file named by an entry stop until it is killed: `NAME` halfway
// through its temporary file (flushed), `NAME:before` before making it.
bool stall_here(const std::string& entry) {
  const char* stall = std::getenv("SHOT_FAULT_STALL");
  return stall && ("," + std::string(stall) + ",").find("," + entry + ",") != std::string::npos;
}

[[noreturn]] void stall(const std::string& what) {
  std::fprintf(stderr, "shot: SHOT_FAULT_STALL: stalled %s\n", what.c_str());
  for (;;) pause();
}

// What open(2) would give a new file: mkstemp makes it 0600, but a shot's
// folder is shared (a group-writable umask on a studio's NFS is common).
mode_t file_mode() {
  static const mode_t mode = [] {
    const mode_t mask = umask(0);
    umask(mask);
    return mode_t(0666 & ~mask);
  }();
  return mode;
}

void write_fully(int fd, const unsigned char* data, size_t size) {
  while (size > 0) {
    const ssize_t n = ::write(fd, data, size);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) throw std::runtime_error(n < 0 ? errno_text() : "nothing written");
    data += n, size -= size_t(n);
  }
}

}  // namespace

uint64_t fnv1a(const void* data, size_t size, uint64_t hash) {
  const auto* p = static_cast<const unsigned char*>(data);
  for (size_t i = 0; i < size; ++i) hash = (hash ^ p[i]) * 0x100000001b3ull;
  return hash;
}

std::vector<unsigned char> frame_bytes(const char* magic, uint32_t version, const std::vector<uint64_t>& fields,
                                       const unsigned char* payload, size_t size) {
  std::vector<unsigned char> out(magic, magic + 8);
  out.reserve(32 + 8 * fields.size() + size);
  put32(out, version);
  put32(out, uint32_t(fields.size()));
  for (uint64_t f : fields) put64(out, f);
  put64(out, size);
  const size_t crc_at = out.size();
  put64(out, 0);
  out.insert(out.end(), payload, payload + size);
  const uint32_t crc = crc32(&out[crc_at + 8], out.size() - crc_at - 8, crc32(out.data(), crc_at));
  for (int i = 0; i < 4; ++i) out[crc_at + size_t(i)] = uint8_t(crc >> (8 * i));
  return out;
}

Framed unframe(const std::string& path, const std::vector<unsigned char>& bytes, const char* magic, uint32_t version,
               size_t field_count) {
  const size_t header = 32 + 8 * field_count;
  if (bytes.size() < 16 || std::memcmp(bytes.data(), magic, 8) != 0) {
    throw std::runtime_error(path + ": not a " + std::string(magic) + " file");
  }
  if (get(&bytes[8], 4) != version || get(&bytes[12], 4) != field_count) {
    throw std::runtime_error(path + ": " + magic + " version " + std::to_string(get(&bytes[8], 4)) +
                             ", this tool reads version " + std::to_string(version));
  }
  if (bytes.size() < header) {
    throw std::runtime_error(path + ": truncated (" + std::to_string(bytes.size()) + " bytes)");
  }
  const size_t crc_at = header - 8;
  const uint64_t length = get(&bytes[crc_at - 8], 8);
  if (length != bytes.size() - header) {
    throw std::runtime_error(path + ": " + std::to_string(bytes.size() - header) + " payload bytes, the header says " +
                             std::to_string(length) + " (truncated or appended to)");
  }
  const uint32_t crc = crc32(&bytes[crc_at + 8], bytes.size() - crc_at - 8, crc32(bytes.data(), crc_at));
  if (crc != get(&bytes[crc_at], 4) || get(&bytes[crc_at + 4], 4) != 0) {
    throw std::runtime_error(path + ": corrupt (CRC mismatch)");
  }
  Framed f;
  for (size_t i = 0; i < field_count; ++i) f.fields.push_back(get(&bytes[16 + 8 * i], 8));
  f.payload = bytes.data() + header;
  f.size = length;
  return f;
}

std::vector<unsigned char> seal(const Identity& id, Kind kind, uint32_t frame, uint32_t sample,
                                const unsigned char* file, size_t size) {
  return frame_bytes(kSealMagic, kSealVersion, {uint64_t(kind), id.shot, id.frames, frame, sample}, file, size);
}

Sealed unseal(const std::string& path, Kind kind) {
  const std::vector<unsigned char> bytes = read_all(path);
  if (bytes.size() < 8 || std::memcmp(bytes.data(), kSealMagic, 8) != 0) {
    throw std::runtime_error(path + ": a file without a shot identity (written before pelage 0.12, or by another"
                                    " tool); the farm reads only files its shot sealed: remove it and resume the shot");
  }
  const Framed f = unframe(path, bytes, kSealMagic, kSealVersion, kSealFields);
  if (f.fields[0] != uint64_t(kind)) {
    throw std::runtime_error(path + ": holds a " + kind_name(f.fields[0]) + ", not a " + kind_name(uint64_t(kind)));
  }
  Sealed s;
  s.id = {f.fields[1], uint32_t(f.fields[2])};
  s.frame = uint32_t(f.fields[3]), s.sample = uint32_t(f.fields[4]);
  s.file.assign(f.payload, f.payload + f.size);
  return s;
}

std::vector<unsigned char> read_sealed(const std::string& path, const Identity& id, Kind kind, uint32_t frame,
                                       uint32_t sample) {
  Sealed s = unseal(path, kind);
  if (!(s.id == id)) {
    throw std::runtime_error(path + ": belongs to another shot (" + hex(s.id.shot) + ", " +
                             std::to_string(s.id.frames) + " frames; this shot is " + hex(id.shot) + ", " +
                             std::to_string(id.frames) + " frames)");
  }
  if (s.frame != frame || s.sample != sample) {
    throw std::runtime_error(path + ": holds " + place(s.frame, s.sample) + " of this shot, not " +
                             place(frame, sample));
  }
  return std::move(s.file);
}

bool sealed_ok(const std::string& path, const Identity& id, Kind kind, uint32_t frame, uint32_t sample) {
  if (access(path.c_str(), F_OK) != 0) return false;
  try {
    read_sealed(path, id, kind, frame, sample);
    return true;
  } catch (const std::runtime_error&) {
    return false;
  }
}

void write_atomic(const std::string& path, const unsigned char* data, size_t size) {
  const size_t slash = path.rfind('/');
  const std::string dir = slash == std::string::npos ? "." : path.substr(0, slash + (slash == 0));
  const std::string base = slash == std::string::npos ? path : path.substr(slash + 1);
  remove_stale_temps(dir, base);
  if (stall_here(base + ":before")) stall("before writing " + path);
  std::string temp = path + ".part-XXXXXX";
  if (temp.size() >= sizeof temp_path) throw std::runtime_error("cannot write " + path + ": path too long");
  const int fd = mkstemp(&temp[0]);
  if (fd < 0) throw std::runtime_error("cannot write " + path + ": " + errno_text());
  std::memcpy(temp_path, temp.c_str(), temp.size() + 1);
  temp_set = 1;
  try {
    if (fchmod(fd, file_mode()) != 0) throw std::runtime_error(errno_text());
    if (stall_here(base)) {
      write_fully(fd, data, size / 2);
      fsync(fd);
      stall("halfway through " + temp);
    }
    write_fully(fd, data, size);
    if (fsync(fd) != 0) throw std::runtime_error(errno_text());
  } catch (const std::runtime_error& e) {
    close(fd);
    unlink(temp.c_str());
    temp_set = 0;
    throw std::runtime_error("cannot write " + path + ": " + e.what());
  }
  if (close(fd) != 0 || rename(temp.c_str(), path.c_str()) != 0) {
    const std::string why = errno_text();
    unlink(temp.c_str());
    temp_set = 0;
    throw std::runtime_error("cannot write " + path + ": " + why);
  }
  temp_set = 0;
  // The rename is durable once the folder is on disk too.
  const int d = open(dir.c_str(), O_RDONLY | O_DIRECTORY);
  if (d >= 0) fsync(d), close(d);
}

void install_signal_cleanup() {
  for (int sig : {SIGTERM, SIGINT, SIGHUP}) std::signal(sig, remove_temp_and_die);
}

std::vector<unsigned char> png_rgb(int width, int height, const std::vector<uint8_t>& rgb, const Identity& id,
                                   uint32_t frame) {
  png_image image;
  std::memset(&image, 0, sizeof image);
  image.version = PNG_IMAGE_VERSION;
  image.width = png_uint_32(width);
  image.height = png_uint_32(height);
  image.format = PNG_FORMAT_RGB;
  png_alloc_size_t size = 0;
  if (!png_image_write_to_memory(&image, nullptr, &size, 0, rgb.data(), 0, nullptr)) {
    throw std::runtime_error(std::string("cannot encode a PNG: ") + image.message);
  }
  std::vector<unsigned char> png(size);
  if (!png_image_write_to_memory(&image, png.data(), &size, 0, rgb.data(), 0, nullptr)) {
    throw std::runtime_error(std::string("cannot encode a PNG: ") + image.message);
  }
  png.resize(size);
  // tEXt right after IHDR (the 8-byte signature, then 25 bytes of IHDR).
  const std::string text = "pelage-shot" + std::string(1, '\0') + "shot=" + hex(id.shot) +
                           " frames=" + std::to_string(id.frames) + " frame=" + std::to_string(frame);
  std::vector<unsigned char> chunk;
  for (int i = 3; i >= 0; --i) chunk.push_back(uint8_t(text.size() >> (8 * i)));
  chunk.insert(chunk.end(), {'t', 'E', 'X', 't'});
  chunk.insert(chunk.end(), text.begin(), text.end());
  const uint32_t crc = crc32(&chunk[4], chunk.size() - 4);
  for (int i = 3; i >= 0; --i) chunk.push_back(uint8_t(crc >> (8 * i)));
  png.insert(png.begin() + 33, chunk.begin(), chunk.end());
  return png;
}

bool png_ok(const std::string& path, const Identity& id, uint32_t frame) {
  if (access(path.c_str(), F_OK) != 0) return false;
  std::vector<unsigned char> png;
  try {
    png = read_all(path);
  } catch (const std::runtime_error&) {
    return false;
  }
  static const unsigned char signature[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1A, '\n'};
  if (png.size() < 8 || std::memcmp(png.data(), signature, 8) != 0) return false;
  const std::string want = "pelage-shot" + std::string(1, '\0') + "shot=" + hex(id.shot) +
                           " frames=" + std::to_string(id.frames) + " frame=" + std::to_string(frame);
  bool named = false;
  for (size_t at = 8; at + 12 <= png.size();) {
    const size_t length = get_be32(&png[at]);
    if (length > png.size() - at - 12) return false;
    const unsigned char* type = &png[at + 4];
    if (crc32(type, 4 + length) != get_be32(&png[at + 8 + length])) return false;
    if (std::memcmp(type, "tEXt", 4) == 0 && length == want.size() && std::memcmp(type + 4, want.data(), length) == 0) {
      named = true;
    }
    at += 12 + length;
    if (std::memcmp(type, "IEND", 4) == 0) return at == png.size() && named;
  }
  return false;
}

}  // namespace farm
