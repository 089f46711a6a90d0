// The parameter list of a pbrt directive: "type name" followed by a value
// or a bracketed list of values, remembering which parameters were read.
#pragma once

#include <cstdint>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "importers/diagnostics.h"
#include "importers/pbrt_tokenizer.h"

namespace yarf::importers {

struct PbrtParam {
  std::string type;  // "float", "rgb", "spectrum", "texture"...
  std::string name;
  SourceLocation where;
  std::vector<double> numbers;       // numeric values
  std::vector<std::string> strings;  // string values
  std::vector<bool> bools;           // bool values
  bool used = false;
  // Given by an Attribute directive for every directive of its kind: no
  // warning when a directive has no use for it.
  bool attribute_default = false;
};

class PbrtParams {
 public:
  // Reads parameters until the next token is not a string.
  static PbrtParams Parse(PbrtTokenizer& tokens);
  // Adds `d` unless the list gives its name already (pbrt-v4's Attribute
  // defaults, which a directive's own parameters override).
  void AddDefault(const PbrtParam& d);
  // The parameters as given, for keeping as defaults.
  const std::vector<PbrtParam>& All() const { return params_; }

  // The parameter (marked as read), or nullptr.
  const PbrtParam* Find(const std::string& name);
  bool Has(const std::string& name) const;
  SourceLocation WhereIs(const std::string& name, const SourceLocation& fallback) const;

  double Float(const std::string& name, double fallback);
  int64_t Integer(const std::string& name, int64_t fallback);
  bool Bool(const std::string& name, bool fallback);
  std::string String(const std::string& name, const std::string& fallback);
  // Every value of a numeric parameter of one of `types` (empty if absent).
  std::vector<double> Numbers(const std::string& name, std::initializer_list<const char*> types);
  // Marks parameters as read without using them (accepted, no effect).
  void Accept(std::initializer_list<const char*> names);
  // Every parameter not read yet, now marked read: what a yarf class named
  // where pbrt names one of its own takes as its properties.
  std::vector<PbrtParam> TakeUnread();

  // One warning per (what, name) never read.
  void WarnUnused(Diagnostics& diagnostics, const std::string& what) const;

 private:
  const PbrtParam& Typed(const std::string& name, std::initializer_list<const char*> types);

  std::vector<PbrtParam> params_;
  // Names the importer looked for, so a misspelt one can be told the nearest.
  mutable std::set<std::string> asked_;
};

}  // namespace yarf::importers
