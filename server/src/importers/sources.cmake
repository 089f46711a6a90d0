# The importers' sources, shared by server/CMakeLists.txt and the fuzzing
# build (fuzz/CMakeLists.txt).
set(YARF_IMPORTER_SOURCES
  diagnostics.cc
  import.cc
  loop_subdivision.cc
  matrix.cc
  measured_media.cc
  mesh_shapes.cc
  named_ior.cc
  numbers.cc
  pbrt_camera.cc
  pbrt_lights.cc
  pbrt_materials.cc
  pbrt_media.cc
  pbrt_params.cc
  pbrt_scene.cc
  pbrt_shapes.cc
  pbrt_spectra.cc
  pbrt_textures.cc
  pbrt_tokenizer.cc
  scene_assembly.cc
  scene_folder.cc
  serialized_mesh.cc
  spectrum.cc
  spectrum_tables.cc
  texture_mean.cc
  volume_file.cc
  xml_bsdf.cc
  xml_document.cc
  xml_emitter.cc
  xml_medium.cc
  xml_plugin.cc
  xml_scene.cc
  xml_sensor.cc
  xml_shape.cc
  xml_texture.cc)
list(TRANSFORM YARF_IMPORTER_SOURCES PREPEND "${CMAKE_CURRENT_LIST_DIR}/")
