#include "importers/pbrt_params.h"

#include <cmath>
#include <sstream>

#include "importers/numbers.h"

namespace yarf::importers {
namespace {

// Parameters that name things rather than count them.
bool StringType(const std::string& type) { return type == "string" || type == "texture"; }
// Parameters that take either (spectra: a name, or wavelength value pairs).
bool EitherType(const std::string& type) { return type == "spectrum"; }

void AddValue(PbrtParam& param, const PbrtToken& token) {
  if (token.kind == PbrtToken::kString) {
    if (param.type == "bool") {
      if (token.text != "true" && token.text != "false")
        Fail(token.where, "bool parameter '" + param.name + "' needs true or false");
      param.bools.push_back(token.text == "true");
    } else if (StringType(param.type) || EitherType(param.type)) {
      param.strings.push_back(token.text);
    } else {
      Fail(token.where, param.type + " parameter '" + param.name + "' needs numbers, got \"" + token.text + "\"");
    }
    return;
  }
  if (param.type == "bool") {
    if (token.text != "true" && token.text != "false")
      Fail(token.where, "bool parameter '" + param.name + "' needs true or false, not '" + token.text + "'");
    param.bools.push_back(token.text == "true");
    return;
  }
  if (StringType(param.type)) Fail(token.where, param.type + " parameter '" + param.name + "' needs a quoted value");
  const auto value = ParseDouble(token.text);
  if (!value) Fail(token.where, "parameter '" + param.name + "': '" + token.text + "' is not a finite number");
  param.numbers.push_back(*value);
}

}  // namespace

PbrtParams PbrtParams::Parse(PbrtTokenizer& tokens) {
  PbrtParams params;
  while (tokens.Peek() && tokens.Peek()->kind == PbrtToken::kString) {
    const PbrtToken declaration = *tokens.Next();
    std::istringstream words(declaration.text);
    PbrtParam param;
    std::string extra;
    if (!(words >> param.type >> param.name) || (words >> extra))
      Fail(declaration.where, "expected a parameter \"type name\", got \"" + declaration.text + "\"");
    param.where = declaration.where;
    // pbrt-v3 spellings of the same types.
    if (param.type == "point") param.type = "point3";
    if (param.type == "vector") param.type = "vector3";
    if (param.type == "normal") param.type = "normal3";
    if (param.type == "color") param.type = "rgb";
    const std::optional<PbrtToken> first = tokens.Next();
    if (!first) Fail(declaration.where, "parameter '" + param.name + "' has no value (the file ends)");
    if (first->kind == PbrtToken::kOpen) {
      for (;;) {
        const std::optional<PbrtToken> token = tokens.Next();
        if (!token) Fail(first->where, "unclosed '[' of parameter '" + param.name + "'");
        if (token->kind == PbrtToken::kClose) break;
        if (token->kind == PbrtToken::kOpen) Fail(token->where, "nested '[' in parameter '" + param.name + "'");
        AddValue(param, *token);
      }
    } else if (first->kind == PbrtToken::kClose) {
      Fail(first->where, "unexpected ']'");
    } else {
      AddValue(param, *first);
    }
    for (const PbrtParam& other : params.params_)
      if (other.name == param.name) Fail(param.where, "parameter '" + param.name + "' is given twice");
    params.params_.push_back(std::move(param));
  }
  return params;
}

const PbrtParam* PbrtParams::Find(const std::string& name) {
  asked_.insert(name);
  for (PbrtParam& p : params_)
    if (p.name == name) {
      p.used = true;
      return &p;
    }
  return nullptr;
}

bool PbrtParams::Has(const std::string& name) const {
  asked_.insert(name);
  for (const PbrtParam& p : params_)
    if (p.name == name) return true;
  return false;
}

SourceLocation PbrtParams::WhereIs(const std::string& name, const SourceLocation& fallback) const {
  for (const PbrtParam& p : params_)
    if (p.name == name) return p.where;
  return fallback;
}

const PbrtParam& PbrtParams::Typed(const std::string& name, std::initializer_list<const char*> types) {
  const PbrtParam& p = *Find(name);
  for (const char* type : types)
    if (p.type == type) return p;
  Fail(p.where, "parameter '" + name + "' has type " + p.type + ", expected " + *types.begin());
}

double PbrtParams::Float(const std::string& name, double fallback) {
  if (!Has(name)) return fallback;
  const PbrtParam& p = Typed(name, {"float", "integer"});
  if (p.numbers.size() != 1) Fail(p.where, "parameter '" + name + "' needs one value");
  return p.numbers[0];
}

int64_t PbrtParams::Integer(const std::string& name, int64_t fallback) {
  if (!Has(name)) return fallback;
  const PbrtParam& p = Typed(name, {"integer"});
  if (p.numbers.size() != 1) Fail(p.where, "parameter '" + name + "' needs one value");
  const double v = p.numbers[0];
  // The range is checked first: converting an out-of-range double is undefined.
  if (!(std::abs(v) <= 9e15) || v != std::trunc(v)) Fail(p.where, "parameter '" + name + "' needs an integer");
  return int64_t(v);
}

bool PbrtParams::Bool(const std::string& name, bool fallback) {
  if (!Has(name)) return fallback;
  const PbrtParam& p = Typed(name, {"bool"});
  if (p.bools.size() != 1) Fail(p.where, "parameter '" + name + "' needs one value");
  return p.bools[0];
}

std::string PbrtParams::String(const std::string& name, const std::string& fallback) {
  if (!Has(name)) return fallback;
  const PbrtParam& p = Typed(name, {"string", "texture"});
  if (p.strings.size() != 1) Fail(p.where, "parameter '" + name + "' needs one value");
  return p.strings[0];
}

std::vector<double> PbrtParams::Numbers(const std::string& name, std::initializer_list<const char*> types) {
  if (!Has(name)) return {};
  return Typed(name, types).numbers;
}

void PbrtParams::Accept(std::initializer_list<const char*> names) {
  for (const char* name : names) Find(name);
}

void PbrtParams::AddDefault(const PbrtParam& d) {
  if (Has(d.name)) return;  // given, or a later default
  params_.push_back(d);
  params_.back().used = false;
  params_.back().attribute_default = true;
}

std::vector<PbrtParam> PbrtParams::TakeUnread() {
  std::vector<PbrtParam> unread;
  for (PbrtParam& p : params_)
    if (!p.used) {
      p.used = true;
      unread.push_back(p);
    }
  return unread;
}

void PbrtParams::WarnUnused(Diagnostics& diagnostics, const std::string& what) const {
  const std::vector<std::string> asked(asked_.begin(), asked_.end());
  for (const PbrtParam& p : params_)
    if (!p.used && !p.attribute_default)
      diagnostics.Warn(p.where, what + ":" + p.name,
                       what + ": parameter '" + p.name + "' ignored" + DidYouMean(p.name, asked));
}

}  // namespace yarf::importers
