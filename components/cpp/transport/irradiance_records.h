// The records of an irradiance cache (Ward, Rubinstein & Clear 1988) with
// their gradients (Ward & Heckbert 1992): storage, the weighted lookup,
// and the cache file.
//
// Records sit in a uniform grid whose cells are as wide as the largest
// radius of influence a record can have (accuracy × largest R), so that a
// lookup visits the 27 cells around the point. Insertion order is kept in
// every cell, so sums run in the same order on every run.
//
// Cache file, native byte order: 8 bytes "yarf-irc", uint32 format version
// (1), uint32 floats per record (28), uint64 key of the scene and settings
// the records were made for, uint64 record count, then the records, each
// position, normal, irradiance (RGB), R, the rotational gradient of R, G
// and B, the translational gradient of R, G and B (3+3+3+1+9+9 floats).
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>
#include <unordered_map>
#include <utility>
#include <vector>

#include "yarf/error.h"
#include "yarf/vecmath.h"

namespace yarf {

struct IrradianceRecord {
  Vec3 position;
  Vec3 normal;  // on the side the record's hemisphere looks to
  Vec3 irradiance;
  float radius = 0;  // harmonic mean distance, clamped
  // ∂E/∂(rotation) and ∂E/∂(translation) of each channel.
  std::array<Vec3, 3> rotational;
  std::array<Vec3, 3> translational;
};

inline constexpr size_t kFloatsPerRecord = 28;

class IrradianceRecords {
 public:
  // accuracy: Ward's a; max_radius: the largest R any record may have.
  IrradianceRecords(float accuracy, float max_radius)
      : accuracy_(accuracy), cell_(std::max(accuracy * max_radius, 1e-6f)) {}

  void Add(const IrradianceRecord& record) {
    cells_[CellKey(Cell(record.position))].push_back(uint32_t(records_.size()));
    records_.push_back(record);
  }
  const std::vector<IrradianceRecord>& All() const { return records_; }
  size_t Size() const { return records_.size(); }

  // Whether some record has weight above 1/a at (p, n): no new record needed.
  bool Covered(Vec3 p, Vec3 n) const {
    bool found = false;
    Visit(p, 1, [&](const IrradianceRecord& r) { found = found || Weight(r, p, n) > 1.0f / accuracy_; });
    return found;
  }

  // E(p, n) = Σ w_i (E_i + (n_i × n)·∇r_i + (p − p_i)·∇t_i) / Σ w_i over
  // the records with w_i > 1/a. Where none qualifies (between the points
  // the cache was made at, or outside the views it was made for) the
  // accuracy is relaxed to 2a, 4a, 8a; then the record of largest weight
  // anywhere gives its value alone; zero when there is none.
  Vec3 Estimate(Vec3 p, Vec3 n) const {
    for (int relax = 1; relax <= 8; relax *= 2) {
      const float threshold = 1.0f / (accuracy_ * float(relax));
      Vec3 sum;
      float weights = 0;
      Visit(p, relax, [&](const IrradianceRecord& r) {
        const float w = Weight(r, p, n);
        if (w <= threshold) return;
        sum += Extrapolate(r, p, n) * w;
        weights += w;
      });
      if (weights > 0) return sum / weights;
    }
    const IrradianceRecord* best = nullptr;
    float best_weight = 0;
    for (const IrradianceRecord& r : records_) {
      const float w = Weight(r, p, n);
      if (w > best_weight) best_weight = w, best = &r;
    }
    return best ? Extrapolate(*best, p, n) : Vec3();
  }

  // Ward's weight 1/(|p − p_i|/R_i + √(1 − n·n_i)); zero for records
  // facing away or lying in front of p (they see what p cannot).
  static float Weight(const IrradianceRecord& r, Vec3 p, Vec3 n) {
    const float cos = Dot(n, r.normal);
    if (cos <= 0) return 0;
    const Vec3 d = p - r.position;
    if (Dot(d, (n + r.normal) * 0.5f) < -0.01f * r.radius) return 0;
    const float error = Length(d) / r.radius + std::sqrt(std::max(0.0f, 1.0f - cos));
    return error > 1e-6f ? 1.0f / error : 1e6f;
  }

 private:
  static Vec3 Extrapolate(const IrradianceRecord& r, Vec3 p, Vec3 n) {
    const Vec3 rotation = Cross(r.normal, n), translation = p - r.position;
    Vec3 e;
    for (int c = 0; c < 3; ++c) {
      const float v = r.irradiance[c] + Dot(rotation, r.rotational[c]) + Dot(translation, r.translational[c]);
      (c == 0 ? e.x : c == 1 ? e.y : e.z) = std::max(0.0f, v);  // gradients may overshoot
    }
    return e;
  }

  std::array<int64_t, 3> Cell(Vec3 p) const {
    return {int64_t(std::floor(p.x / cell_)), int64_t(std::floor(p.y / cell_)), int64_t(std::floor(p.z / cell_))};
  }
  static uint64_t CellKey(const std::array<int64_t, 3>& c) {
    return (uint64_t(c[0]) * 73856093u) ^ (uint64_t(c[1]) * 19349663u) ^ (uint64_t(c[2]) * 83492791u);
  }
  // Calls f on every record of the cells within `reach` cells of p's
  // (records from colliding cells too: the weight sorts them out).
  template <typename F>
  void Visit(Vec3 p, int reach, F&& f) const {
    const auto c = Cell(p);
    for (int64_t x = -reach; x <= reach; ++x)
      for (int64_t y = -reach; y <= reach; ++y)
        for (int64_t z = -reach; z <= reach; ++z) {
          const auto it = cells_.find(CellKey({c[0] + x, c[1] + y, c[2] + z}));
          if (it == cells_.end()) continue;
          for (uint32_t i : it->second) f(records_[i]);
        }
  }

  float accuracy_;
  float cell_;
  std::vector<IrradianceRecord> records_;
  std::unordered_map<uint64_t, std::vector<uint32_t>> cells_;
};

// The cache file (format above).
namespace irradiance_file {

inline constexpr char kMagic[8] = {'y', 'a', 'r', 'f', '-', 'i', 'r', 'c'};
inline constexpr uint32_t kVersion = 1;

inline std::array<float, kFloatsPerRecord> Pack(const IrradianceRecord& r) {
  std::array<float, kFloatsPerRecord> f{};
  size_t i = 0;
  auto put = [&](Vec3 v) { v.Store(&f[i]), i += 3; };
  put(r.position), put(r.normal), put(r.irradiance);
  f[i++] = r.radius;
  for (Vec3 g : r.rotational) put(g);
  for (Vec3 g : r.translational) put(g);
  return f;
}

inline IrradianceRecord Unpack(const std::array<float, kFloatsPerRecord>& f) {
  IrradianceRecord r;
  size_t i = 0;
  auto get = [&] { const Vec3 v = Vec3::Load(&f[i]); i += 3; return v; };
  r.position = get(), r.normal = get(), r.irradiance = get();
  r.radius = f[i++];
  for (Vec3& g : r.rotational) g = get();
  for (Vec3& g : r.translational) g = get();
  return r;
}

// Whether a record read from a file can be used: finite numbers a scene
// may hold, a positive radius, a unit normal. The file is untrusted: a NaN
// would poison every estimate, a huge position the cell arithmetic.
inline bool Sound(const IrradianceRecord& r) {
  const auto bounded = [](Vec3 v) {
    return std::abs(v.x) <= 1e12f && std::abs(v.y) <= 1e12f && std::abs(v.z) <= 1e12f;
  };
  bool all = bounded(r.position) && bounded(r.irradiance) && r.radius > 0 && r.radius <= 1e12f &&
             std::abs(Length(r.normal) - 1) < 1e-3f;
  for (int c = 0; c < 3; ++c) all = all && bounded(r.rotational[c]) && bounded(r.translational[c]);
  return all;
}

// The records stored at `path` for `key`; false when the file is missing,
// unreadable, damaged or made for another scene or settings.
inline bool Read(const std::string& path, uint64_t key, std::vector<IrradianceRecord>& out) {
  std::ifstream in(path, std::ios::binary | std::ios::ate);
  if (!in) return false;
  const uint64_t file_size = uint64_t(in.tellg());
  in.seekg(0);
  char magic[8];
  uint32_t version = 0, floats = 0;
  uint64_t stored_key = 0, count = 0;
  in.read(magic, 8);
  in.read(reinterpret_cast<char*>(&version), 4);
  in.read(reinterpret_cast<char*>(&floats), 4);
  in.read(reinterpret_cast<char*>(&stored_key), 8);
  in.read(reinterpret_cast<char*>(&count), 8);
  if (!in || std::memcmp(magic, kMagic, 8) != 0 || version != kVersion || floats != kFloatsPerRecord ||
      stored_key != key)
    return false;
  // The count the bytes can hold, before anything is allocated.
  constexpr uint64_t kHeader = 32, kRecordBytes = kFloatsPerRecord * sizeof(float);
  if (count != (file_size - kHeader) / kRecordBytes) return false;
  std::vector<IrradianceRecord> records;
  records.reserve(count);
  for (uint64_t k = 0; k < count; ++k) {
    std::array<float, kFloatsPerRecord> f;
    if (!in.read(reinterpret_cast<char*>(f.data()), sizeof f)) return false;
    records.push_back(Unpack(f));
    if (!Sound(records.back())) return false;
  }
  out = std::move(records);
  return true;
}

// Writes through a temporary file and a rename, so that a reader never
// sees half a cache.
inline void Write(const std::string& path, uint64_t key, const std::vector<IrradianceRecord>& records) {
  const std::string partial = path + ".partial";
  {
    std::ofstream out(partial, std::ios::binary | std::ios::trunc);
    if (!out) throw Error("irradiance_cache: cannot write cache_file '" + path + "'");
    const uint32_t version = kVersion, floats = kFloatsPerRecord;
    const uint64_t count = records.size();
    out.write(kMagic, 8);
    out.write(reinterpret_cast<const char*>(&version), 4);
    out.write(reinterpret_cast<const char*>(&floats), 4);
    out.write(reinterpret_cast<const char*>(&key), 8);
    out.write(reinterpret_cast<const char*>(&count), 8);
    for (const IrradianceRecord& r : records) {
      const auto f = Pack(r);
      out.write(reinterpret_cast<const char*>(f.data()), sizeof f);
    }
    if (!out) throw Error("irradiance_cache: cannot write cache_file '" + path + "'");
  }
  std::error_code error;
  std::filesystem::rename(partial, path, error);
  if (error) throw Error("irradiance_cache: cannot write cache_file '" + path + "': " + error.message());
}

}  // namespace irradiance_file
}  // namespace yarf
