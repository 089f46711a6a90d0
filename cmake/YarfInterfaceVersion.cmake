# yarf_interface_version(HEADERS_DIR OUT_DIR): writes OUT_DIR/yarf/interface_version.h
# with the interface version: the first 16 hex digits of the SHA-256 of the
# interface headers in HEADERS_DIR/yarf, names and text, so that yarfd refuses
# a plugin built against other headers instead of calling into a layout it
# does not share. Editing a header re-runs CMake.
function(yarf_interface_version headers_dir out_dir)
  file(GLOB headers "${headers_dir}/yarf/*.h")
  list(SORT headers)
  set_property(DIRECTORY APPEND PROPERTY CMAKE_CONFIGURE_DEPENDS ${headers})
  set(text "")
  foreach(header IN LISTS headers)
    get_filename_component(name "${header}" NAME)
    file(READ "${header}" content)
    string(APPEND text "${name}\n${content}")
  endforeach()
  string(SHA256 hash "${text}")
  string(SUBSTRING "${hash}" 0 16 YARF_INTERFACE_VERSION)
  configure_file("${headers_dir}/yarf/interface_version.h.in" "${out_dir}/yarf/interface_version.h" @ONLY)
endfunction()
