# yarf_add_plugin(NAME SOURCE...): a plugin yarfd loads from its plugin
# folders (--plugin-path): the shared library libyarf_NAME.so, C++20,
# built against yarf's interface headers with only its entry points
# visible. The same rule builds the plugins of yarf's tree and those built
# against an installed yarf (find_package(yarf)).
function(yarf_add_plugin name)
  add_library(${name} MODULE ${ARGN})
  target_link_libraries(${name} PRIVATE yarf::interfaces)
  target_compile_features(${name} PRIVATE cxx_std_20)
  set_target_properties(${name} PROPERTIES
    PREFIX "lib" OUTPUT_NAME "yarf_${name}"
    CXX_VISIBILITY_PRESET hidden)
endfunction()
