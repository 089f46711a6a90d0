// tinyobjloader's implementation, compiled into the fuzzers with their
// instrumentation (the system's shared library has none).
#define TINYOBJLOADER_IMPLEMENTATION
#include <tiny_obj_loader.h>
