#include "service/user_files.h"

#include <openssl/sha.h>

#include <algorithm>
#include <system_error>

#include "yarf/error.h"

namespace yarf {
namespace {

bool IsPlainName(const std::string& name) {
  const auto plain = [](char c) {
    return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_' || c == '-';
  };
  return !name.empty() && name.size() <= 64 && std::all_of(name.begin(), name.end(), plain);
}

std::string HexSha256(const std::string& text) {
  unsigned char digest[SHA256_DIGEST_LENGTH];
  SHA256(reinterpret_cast<const unsigned char*>(text.data()), text.size(), digest);
  static constexpr char kHex[] = "0123456789abcdef";
  std::string hex;
  for (unsigned char byte : digest) hex += {kHex[byte >> 4], kHex[byte & 15]};
  return hex;
}

}  // namespace

std::string UserFolderName(const std::string& user) { return IsPlainName(user) ? user : "~" + HexSha256(user); }

std::filesystem::path UserFileFolder(const std::filesystem::path& root, const std::string& user) {
  namespace fs = std::filesystem;
  const fs::path folder = root / UserFolderName(user);
  std::error_code error;
  fs::create_directories(folder, error);
  if (!error) fs::permissions(folder, fs::perms::owner_all, fs::perm_options::replace, error);
  if (error) throw Error("cannot make the file folder " + folder.string() + ": " + error.message());
  return folder;
}

}  // namespace yarf
