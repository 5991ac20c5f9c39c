# SPDX-License-Identifier: Apache-2.0
# Project-wide warning flags, applied per target with rsu_warnings(target), which also registers the
# target for the shared precompiled headers of the clang trees (cmake/precompiled_headers.cmake).
include(${CMAKE_CURRENT_LIST_DIR}/precompiled_headers.cmake)
function(rsu_warnings target)
  target_compile_options(${target} PRIVATE -Wall -Wextra -Wpedantic -Wshadow -Wnon-virtual-dtor
                                           -Wold-style-cast -Wcast-align -Woverloaded-virtual
                                           -Wdouble-promotion -Wformat=2)
  # GCC 12 reports -Wrestrict inside libstdc++'s std::string at -O3 (a known false positive, fixed in
  # GCC 13); it fires on plain string concatenation in our code.
  if(CMAKE_CXX_COMPILER_ID STREQUAL "GNU" AND CMAKE_CXX_COMPILER_VERSION VERSION_LESS 13)
    target_compile_options(${target} PRIVATE -Wno-restrict)
  endif()
  if(RSU_WERROR)
    target_compile_options(${target} PRIVATE -Werror)
  endif()
  rsu_register_for_precompiled_headers(${target})
endfunction()
