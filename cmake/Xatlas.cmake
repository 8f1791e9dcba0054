# xatlas as a static library, from the source distribution scripts/setup fetched (cmake/xatlas.env
# pins its version and hash). Nothing of it is kept in the repository.
file(STRINGS ${CMAKE_CURRENT_LIST_DIR}/xatlas.env XATLAS_PIN REGEX "^XATLAS_")
string(REGEX REPLACE ".*XATLAS_VERSION=([^;]+).*" "\\1" XATLAS_VERSION "${XATLAS_PIN}")
string(REGEX REPLACE ".*XATLAS_SHA256=([0-9a-f]+).*" "\\1" XATLAS_SHA256 "${XATLAS_PIN}")
set(XATLAS_SDIST ${PROJECT_SOURCE_DIR}/.deps/xatlas-${XATLAS_VERSION}.tar.gz)
if(NOT EXISTS ${XATLAS_SDIST})
  message(FATAL_ERROR "xatlas: ${XATLAS_SDIST} is missing: run scripts/setup")
endif()
file(SHA256 ${XATLAS_SDIST} XATLAS_GOT)
if(NOT XATLAS_GOT STREQUAL XATLAS_SHA256)
  message(FATAL_ERROR "xatlas: ${XATLAS_SDIST} has SHA-256 ${XATLAS_GOT}, not the pinned "
                      "${XATLAS_SHA256}: delete it and run scripts/setup")
endif()
set(XATLAS_DIR ${CMAKE_BINARY_DIR}/_deps/xatlas-${XATLAS_VERSION}/extern/xatlas/source/xatlas)
if(NOT EXISTS ${XATLAS_DIR}/xatlas.cpp)
  file(ARCHIVE_EXTRACT INPUT ${XATLAS_SDIST} DESTINATION ${CMAKE_BINARY_DIR}/_deps
       PATTERNS xatlas-${XATLAS_VERSION}/extern/xatlas/source/xatlas/*
                xatlas-${XATLAS_VERSION}/extern/xatlas/LICENSE)
endif()
add_library(xatlas STATIC ${XATLAS_DIR}/xatlas.cpp)
target_include_directories(xatlas SYSTEM PUBLIC ${XATLAS_DIR})
set_target_properties(xatlas PROPERTIES POSITION_INDEPENDENT_CODE ON)
target_compile_options(xatlas PRIVATE -w)  # not our code: its warnings are not ours to fix
target_link_libraries(xatlas PRIVATE Threads::Threads)
