// An entry point built against other interface headers.
extern "C" __attribute__((visibility("default"))) const char* yarf_interface_version() { return "0123456789abcdef"; }
extern "C" __attribute__((visibility("default"))) void yarf_register_components(void*) {}
