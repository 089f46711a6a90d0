// What a job keeps in the state folder beside its database row: the
// checkpoint of its film while it renders, and its image once it ends.
#pragma once

#include <cstdint>
#include <filesystem>
#include <optional>
#include <utility>
#include <vector>

#include "kernel/film.h"

namespace yarf {

// A film saved after `samples_done` samples per pixel.
struct FilmCheckpoint {
  uint32_t samples_done;
  Film film;
};

// `film` is Film::Save()'s bytes (taken under the film's lock).
void WriteCheckpoint(const std::filesystem::path& path, uint32_t samples_done, const std::string& film);
// nullopt when there is none; throws Error for a damaged one.
std::optional<FilmCheckpoint> ReadCheckpoint(const std::filesystem::path& path);

// A job's final pixel estimates and their variances, row-major [height, width, 3].
struct JobImage {
  uint32_t width = 0, height = 0;
  std::vector<float> pixels, variances;
};

void WriteJobImage(const std::filesystem::path& path, const JobImage& image);
// nullopt when there is none; throws Error for a damaged one.
std::optional<JobImage> ReadJobImage(const std::filesystem::path& path);
// The width and height of a job's image, from its header only.
std::optional<std::pair<uint32_t, uint32_t>> ReadJobImageSize(const std::filesystem::path& path);

}  // namespace yarf
