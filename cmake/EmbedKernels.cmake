# Embeds every OpenCL source under kernels/ into a generated C++ file.
# The custom command DEPENDS on each .cl/.h so an edit to any kernel or shared
# header regenerates the table and relinks the binaries that use it.
function(luxel_embed_kernels target kernel_dir)
  file(GLOB_RECURSE _sources CONFIGURE_DEPENDS
       "${kernel_dir}/*.cl" "${kernel_dir}/*.h")
  set(_out "${CMAKE_CURRENT_BINARY_DIR}/embedded_kernels.cpp")
  add_custom_command(
    OUTPUT "${_out}"
    COMMAND ${CMAKE_COMMAND} -DKERNEL_DIR=${kernel_dir} -DOUT=${_out}
            -P "${PROJECT_SOURCE_DIR}/cmake/EmbedKernelsScript.cmake"
    DEPENDS ${_sources} "${PROJECT_SOURCE_DIR}/cmake/EmbedKernelsScript.cmake"
    COMMENT "Embedding OpenCL kernel sources"
    VERBATIM)
  add_library(${target} STATIC "${_out}")
  target_link_libraries(${target} PRIVATE luxel_warnings)
endfunction()
