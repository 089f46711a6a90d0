// An entry point from before plugins said their interface version.
extern "C" __attribute__((visibility("default"))) void yarf_register_components(void*) {}
