// yarf-import — converts a Mitsuba 3 (.xml) or pbrt-v4 (.pbrt) scene into
// yarf's own Scene (protobuf JSON or text format).
//
//   yarf-import IN.(xml|pbrt) [-o OUT.json|OUT.textproto] [-D name=value]... [--strict] [--confine]
//
// The scene goes to stdout as JSON, or to OUT in the format its extension
// names. On stderr: one "warning: file:line: ..." line per construct that
// was ignored or approximated, and "info: sample_count N" when the file
// asks for a number of samples per pixel, "info: crop x0,x1,y0,y1" when it
// renders only part of its film (yarf's render options carry them, not the
// Scene). Mesh files stay files, named relative to IN's folder.
// -D sets a Mitsuba scene parameter ($name), overriding its <default>.
// --strict makes every warning an error: nothing is ignored or approximated.
// --confine finds only files inside IN's folder (symbolic links followed),
// for a scene from someone else.
//
// Exit status: 0 on success, 2 when IN cannot be imported (one line on
// stderr: "yarf-import: error: file:line: message") or the command line
// is wrong, 1 when OUT cannot be written.
#include <google/protobuf/text_format.h>
#include <google/protobuf/util/json_util.h>

#include <cstring>
#include <fstream>
#include <iostream>
#include <string>

#include "importers/import.h"

namespace {

constexpr const char* kUsage =
    "usage: yarf-import IN.(xml|pbrt) [-o OUT.json|OUT.textproto] [-D name=value]... [--strict] [--confine]\n";

int UsageError(const std::string& message) {
  std::cerr << "yarf-import: error: " << message << "\n" << kUsage;
  return 2;
}

bool EndsWith(const std::string& s, const std::string& suffix) {
  return s.size() >= suffix.size() && s.compare(s.size() - suffix.size(), suffix.size(), suffix) == 0;
}

}  // namespace

int main(int argc, char** argv) {
  std::string input, output;
  bool strict = false;
  yarf::importers::ImportOptions options;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg == "-h" || arg == "--help") {
      std::cout << kUsage;
      return 0;
    }
    if (arg == "--strict") {
      strict = true;
      continue;
    }
    if (arg == "--confine") {
      options.confine_to_folder = true;
      continue;
    }
    if (arg == "-o" || arg == "-D") {
      if (i + 1 >= argc) return UsageError(arg + " needs a value");
      const std::string value = argv[++i];
      if (arg == "-o") {
        output = value;
        continue;
      }
      const size_t equals = value.find('=');
      if (equals == std::string::npos || equals == 0) return UsageError("-D needs name=value, got '" + value + "'");
      options.parameters[value.substr(0, equals)] = value.substr(equals + 1);
    } else if (!arg.empty() && arg[0] == '-' && arg != "-") {
      return UsageError("unknown option " + arg);
    } else if (input.empty()) {
      input = arg;
    } else {
      return UsageError("more than one input file");
    }
  }
  if (input.empty()) return UsageError("no input file");
  const bool text_format = EndsWith(output, ".textproto") || EndsWith(output, ".pbtxt") || EndsWith(output, ".txtpb");
  if (!output.empty() && !text_format && !EndsWith(output, ".json"))
    return UsageError("the output must end in .json or .textproto");

  yarf::importers::ImportResult result;
  try {
    result = yarf::importers::ImportSceneFile(input, options);
  } catch (const yarf::importers::ImportError& error) {
    std::cerr << "yarf-import: error: " << error.what() << "\n";
    return 2;
  } catch (const std::exception& error) {
    // Anything else the libraries raise on a malformed file.
    std::cerr << "yarf-import: error: " << input << ": " << error.what() << "\n";
    return 2;
  }
  for (const std::string& warning : result.warnings) std::cerr << "warning: " << warning << "\n";
  if (strict && !result.warnings.empty()) {
    const size_t more = result.warnings.size() - 1;
    std::cerr << "yarf-import: error: " << result.warnings.front()
              << (more ? " (and " + std::to_string(more) + " more warning" + (more > 1 ? "s" : "") + ")" : "")
              << "; --strict refuses what would be ignored or approximated\n";
    return 2;
  }
  if (result.sample_count > 0) std::cerr << "info: sample_count " << result.sample_count << "\n";
  if (!result.crop.empty()) std::cerr << "info: crop " << result.crop << "\n";

  std::string text;
  if (text_format) {
    google::protobuf::TextFormat::PrintToString(result.scene, &text);
  } else {
    google::protobuf::util::JsonPrintOptions json;
    json.add_whitespace = true;
    json.preserve_proto_field_names = true;
    if (!google::protobuf::util::MessageToJsonString(result.scene, &text, json).ok()) {
      std::cerr << "yarf-import: error: cannot print the scene as JSON\n";
      return 1;
    }
  }
  if (output.empty()) {
    std::cout << text;
    return std::cout.flush() ? 0 : 1;
  }
  std::ofstream out(output, std::ios::binary);
  if (!(out << text) || !out.flush()) {
    std::cerr << "yarf-import: error: cannot write " << output << ": " << std::strerror(errno) << "\n";
    return 1;
  }
  return 0;
}
