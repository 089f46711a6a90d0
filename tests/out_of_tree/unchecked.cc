// Plugins yarfd refuses once it has called them: a schema it cannot check,
// and an entry point that throws. Either refusal leaves yarfd serving.
#include <stdexcept>

#include "yarf/plugin.h"

namespace {

class Grey : public yarf::Function {
 public:
  explicit Grey(const yarf::Properties&) {}
  uint32_t InputDimensions() const override { return 1; }
  uint32_t OutputDimensions() const override { return 1; }
  void Evaluate(std::span<const float>, std::span<float> values) override {
    for (float& value : values) value = 0.5f;
  }
};

// A parameter without a name.
struct Unnamed final : Grey {
  using Grey::Grey;
  static yarf::ParameterSchema Parameters() { return {yarf::Parameter::Float("").Doc("no name")}; }
};

// The plugin's own exception type: its type information lives in the plugin.
struct PluginError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

}  // namespace

YARF_PLUGIN(registrar) {
#ifdef YARF_THROWS
  yarf::Register<Grey>(registrar, "oot_thrower", "1.0.0", "registered, then the entry point throws");
  throw PluginError("the entry point gave up");
#else
  yarf::Register<Unnamed>(registrar, "oot_unnamed", "1.0.0", "a parameter without a name");
#endif
}
