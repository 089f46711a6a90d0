// What a job keeps in the state folder beside its database row: the
// checkpoint of its film while it renders, and its image once it ends.
// Each file names the job and the attempt that wrote it and ends with a
// SHA-256 of the rest, so that a file swapped in from another job, edited
// or damaged is refused rather than served or resumed.
#pragma once

#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "kernel/film.h"

namespace yarf {

// Whose file it is: the job's number and the attempt (the run, counted
// from 1) that wrote it.
struct JobFileOwner {
  uint64_t job_number = 0;
  uint32_t attempt = 0;
};

// A film saved after `samples_done` samples per pixel by run `attempt`.
struct FilmCheckpoint {
  uint32_t samples_done;
  uint32_t attempt;
  Film film;
};

// `film` is Film::Save()'s bytes (taken under the film's lock).
void WriteCheckpoint(const std::filesystem::path& path, const JobFileOwner& owner, uint32_t samples_done,
                     const std::string& film);
// nullopt when there is none. Throws Error for a damaged file, one of
// another job, or one written by a later attempt than `reader.attempt`:
// a checkpoint of an earlier attempt is what a run after a crash or a stop
// resumes from, so it is accepted; one of a later attempt cannot have been
// written for the row that reads it.
std::optional<FilmCheckpoint> ReadCheckpoint(const std::filesystem::path& path, const JobFileOwner& reader);

// A job's final pixel estimates and their variances, row-major [height, width, 3].
struct JobImage {
  uint32_t width = 0, height = 0;
  std::vector<float> pixels, variances;
};

void WriteJobImage(const std::filesystem::path& path, const JobFileOwner& owner, const JobImage& image);
// Where the image of the arbitrary output variable `aov` of the job whose
// image is at `result` lies: beside it.
inline std::filesystem::path AovImagePath(const std::filesystem::path& result, std::string_view aov) {
  std::filesystem::path path = result;
  path.replace_extension(std::string(aov) + result.extension().string());
  return path;
}
// nullopt when there is none. Throws Error for a damaged file or one that
// is not `owner`'s: an ended job's attempts no longer change, so its image
// was written by exactly its last attempt.
std::optional<JobImage> ReadJobImage(const std::filesystem::path& path, const JobFileOwner& owner);
// The width and height of `owner`'s image, from its header only: the
// owner is checked, the checksum only by ReadJobImage.
std::optional<std::pair<uint32_t, uint32_t>> ReadJobImageSize(const std::filesystem::path& path,
                                                              const JobFileOwner& owner);
// Rewrites an image an older yarfd wrote (without owner and checksum) as
// `owner`'s; true if it did. Only for the first start after an upgrade:
// until then nothing could have bound the file to its job.
bool UpgradeLegacyJobImage(const std::filesystem::path& path, const JobFileOwner& owner);

}  // namespace yarf
