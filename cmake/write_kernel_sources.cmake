# Script mode: writes OUT, a C++ file defining shadow::cl::kernel_source(name) over the
# KERNEL_DIR/*.cl files.
file(GLOB FILES ${KERNEL_DIR}/*.cl)
set(body "// Generated from kernels/*.cl by cmake/write_kernel_sources.cmake. Do not edit.\n")
string(APPEND body "#include <string_view>\n#include <stdexcept>\n#include <string>\n")
string(APPEND body "namespace shadow::cl {\nstd::string_view kernel_source(std::string_view name) {\n")
foreach(f ${FILES})
  get_filename_component(name ${f} NAME)
  file(READ ${f} text)
  string(APPEND body "  if (name == \"${name}\") return R\"CLSRC(${text})CLSRC\";\n")
endforeach()
string(APPEND body "  throw std::invalid_argument(\"no embedded kernel named \" + std::string(name));\n}\n}\n")
file(WRITE ${OUT}.tmp "${body}")
file(COPY_FILE ${OUT}.tmp ${OUT} ONLY_IF_DIFFERENT)
