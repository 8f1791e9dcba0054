# Embeds kernels/*.cl into a generated C++ source at build time, so the binaries carry their
# kernels and a kernel edit rebuilds only that one file.
file(GLOB SHADOW_KERNEL_FILES CONFIGURE_DEPENDS ${PROJECT_SOURCE_DIR}/kernels/*.cl)
set(SHADOW_KERNELS_CPP ${CMAKE_BINARY_DIR}/generated/kernel_sources.cpp)
add_custom_command(
  OUTPUT ${SHADOW_KERNELS_CPP}
  COMMAND ${CMAKE_COMMAND} -DOUT=${SHADOW_KERNELS_CPP} -DKERNEL_DIR=${PROJECT_SOURCE_DIR}/kernels
          -P ${PROJECT_SOURCE_DIR}/cmake/write_kernel_sources.cmake
  DEPENDS ${SHADOW_KERNEL_FILES} ${PROJECT_SOURCE_DIR}/cmake/write_kernel_sources.cmake
  COMMENT "Embedding OpenCL kernels")
