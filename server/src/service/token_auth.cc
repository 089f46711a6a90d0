#include "service/token_auth.h"

#include <algorithm>
#include <array>
#include <cctype>
#include <fstream>
#include <optional>
#include <sstream>

#include "yarf/error.h"

namespace yarf {
namespace {

// Only these change the server for every user. Left open to submit tokens:
// - RenderService: each call acts on one job; the service checks its owner.
// - AssetService.Upload/Missing: assets are stored by their verified hash,
//   so an upload can add a file but never replace one.
// - Registry.ListClasses, Component.Describe: read only.
// - Factory and the instance services (SurfaceModel, Sampler, ...): they
//   compute on instances made for the caller and change nothing shared.
constexpr std::array<std::string_view, 3> kAdminMethods = {
    "/yarf.v1.Registry/LoadPlugin",
    "/yarf.v1.Registry/Register",
    "/yarf.v1.Registry/Unregister",
};
// The running jobs' scenes, served to transports in component processes
// (which an admin registers, with an admin token): their handles name any
// user's job.
constexpr std::array<std::string_view, 5> kAdminServices = {
    "/yarf.v1.SceneView/",           "/yarf.v1.Intersect/", "/yarf.v1.Shape/", "/yarf.v1.SampleSurfaceArea/",
    "/yarf.v1.SampleSurfaceDirection/",
};

constexpr std::string_view kBearer = "bearer ";

std::string_view View(const grpc::string_ref& ref) { return {ref.data(), ref.size()}; }

std::string_view Find(const grpc::AuthMetadataProcessor::InputMetadata& metadata, std::string_view key) {
  const auto found = metadata.find(grpc::string_ref(key.data(), key.size()));
  return found == metadata.end() ? std::string_view() : View(found->second);
}

// The token of `Bearer TOKEN` (the scheme in any case, as HTTP allows), or "".
std::string_view BearerToken(std::string_view header) {
  if (header.size() <= kBearer.size()) return {};
  const bool bearer = std::equal(kBearer.begin(), kBearer.end(), header.begin(),
                                 [](char a, char b) { return a == std::tolower(static_cast<unsigned char>(b)); });
  return bearer ? header.substr(kBearer.size()) : std::string_view();
}

std::optional<Role> ParseRole(const std::string& name) {
  if (name == RoleName(Role::kSubmit)) return Role::kSubmit;
  if (name == RoleName(Role::kAdmin)) return Role::kAdmin;
  return std::nullopt;
}

}  // namespace

TokenTable ReadTokenFile(const std::filesystem::path& path) {
  std::ifstream file(path);
  if (!file) throw Error("cannot read the tokens file " + path.string());
  TokenTable tokens;
  int number = 0;
  for (std::string line; std::getline(file, line);) {
    ++number;
    const std::string where = path.string() + " line " + std::to_string(number);
    std::istringstream fields(line.substr(0, line.find('#')));
    std::string token, user, role_name, extra;
    fields >> token >> user >> role_name >> extra;
    if (token.empty()) continue;  // blank or a comment
    if (role_name.empty() || !extra.empty())
      throw Error(where + ": expected `TOKEN USER ROLE` (three fields separated by spaces)");
    const auto role = ParseRole(role_name);
    if (!role) throw Error(where + ": role '" + role_name + "' is neither submit nor admin");
    if (!tokens.emplace(token, Caller{user, *role}).second)
      throw Error(where + ": this token is already given to " + tokens.at(token).user);
  }
  if (tokens.empty()) throw Error("the tokens file " + path.string() + " holds no token");
  return tokens;
}

bool IsOpenMethod(std::string_view method) {
  return method.starts_with("/grpc.health.v1.Health/") || method.starts_with("/grpc.reflection.");
}

bool IsAdminMethod(std::string_view method) {
  const auto in_service = [&](std::string_view service) { return method.starts_with(service); };
  return std::find(kAdminMethods.begin(), kAdminMethods.end(), method) != kAdminMethods.end() ||
         std::any_of(kAdminServices.begin(), kAdminServices.end(), in_service);
}

TokenAuthProcessor::TokenAuthProcessor(TokenTable tokens) : tokens_(std::move(tokens)) {}

grpc::Status TokenAuthProcessor::Process(const InputMetadata& auth_metadata, grpc::AuthContext* context,
                                         OutputMetadata* consumed_auth_metadata, OutputMetadata*) {
  const std::string_view method = Find(auth_metadata, ":path");
  // The role check needs the method: never let a call through without it.
  if (method.empty()) return {grpc::StatusCode::INTERNAL, "the call names no method"};
  const std::string_view header = Find(auth_metadata, "authorization");
  if (header.empty()) {
    if (IsOpenMethod(method)) return grpc::Status::OK;
    return {grpc::StatusCode::UNAUTHENTICATED, "yarfd needs a token: send `authorization: Bearer TOKEN`"};
  }
  const std::string_view token = BearerToken(header);
  if (token.empty())
    return {grpc::StatusCode::UNAUTHENTICATED, "the authorization header must read `Bearer TOKEN`"};
  const auto found = tokens_.find(std::string(token));
  if (found == tokens_.end()) return {grpc::StatusCode::UNAUTHENTICATED, "unknown token"};
  const Caller& caller = found->second;
  if (caller.role != Role::kAdmin && IsAdminMethod(method))
    return {grpc::StatusCode::PERMISSION_DENIED,
            std::string(method) + " needs an admin token; " + caller.user + " has the submit role"};
  // The services never see the token itself.
  consumed_auth_metadata->emplace("authorization", std::string(header));
  const std::scoped_lock lock(binding_);
  const auto bound = context->FindPropertyValues(kUserProperty);
  if (bound.empty()) {
    context->AddProperty(kUserProperty, caller.user);
    context->AddProperty(kRoleProperty, std::string(RoleName(caller.role)));
    return grpc::Status::OK;
  }
  const auto role = context->FindPropertyValues(kRoleProperty);
  if (View(bound.front()) != caller.user || role.empty() || View(role.front()) != RoleName(caller.role))
    return {grpc::StatusCode::UNAUTHENTICATED,
            "this connection already carries another user's token: use one connection per token"};
  return grpc::Status::OK;
}

}  // namespace yarf
