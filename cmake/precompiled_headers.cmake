# SPDX-License-Identifier: Apache-2.0
# With clang (the ASan+UBSan and TSan trees, scripts/build.sh), one precompiled header for the
# libraries, daemon and tools: Eigen and the standard headers most of their sources include. The test
# binaries have their own (gtest, at -O0: tests/CMakeLists.txt), with either compiler.
#
# Measured on the ten lib/ libraries (113 sources, 2 cores, from scratch): clang with ASan+UBSan at -O1
# 203 -> 147 s; GCC at -O3 (Release) 173 -> 153 s, and there GCC 12 then reports its known false
# positives inside std::string (-Warray-bounds, -Wstringop-overflow) at two of our lines, which -Werror
# turns into errors. So a GCC tree (Release) keeps its sources' own includes.
#
# A precompiled header is valid only for sources compiled with the same options: GCC and clang reject
# one built without -fPIC for a -fPIC source, clang one built without the fuzzer's instrumentation
# (fuzz/) for an instrumented source. So each set of compile options gets its own header, built once by
# an object library rsu_pch_<hash>; every target that rsu_warnings() saw reuses the one for its
# options. The choice is made at the end of the configure step (rsu_apply_precompiled_headers(), called
# by the top-level CMakeLists.txt), once every folder has set its targets' options and PIC. A mismatch
# missed here fails the build (clang refuses the header), never silently. Options that linked libraries
# add are not seen here: a target linking Qt (through PCL's VTK), which adds -fPIC, says
# POSITION_INDEPENDENT_CODE itself. Extra -D definitions do not invalidate the header.
#
# Every source then sees these headers whether it includes them or not; the Release tree (GCC) does
# not, so a missing include still fails there.
set(RSU_PRECOMPILED_HEADERS
    <Eigen/Core> <Eigen/Geometry> <Eigen/Cholesky> <algorithm> <array> <cmath> <cstddef> <cstdint>
    <limits> <optional> <span> <stdexcept> <string> <utility> <vector>)

# Called by rsu_warnings() for every target of ours.
function(rsu_register_for_precompiled_headers target)
  set_property(GLOBAL APPEND PROPERTY RSU_PRECOMPILED_HEADER_TARGETS ${target})
endfunction()

function(rsu_apply_precompiled_headers)
  if(NOT CMAKE_CXX_COMPILER_ID STREQUAL "Clang")
    return()
  endif()
  get_property(targets GLOBAL PROPERTY RSU_PRECOMPILED_HEADER_TARGETS)
  set(owners "")
  set(users 0)
  foreach(target IN LISTS targets)
    get_target_property(reused ${target} PRECOMPILE_HEADERS_REUSE_FROM)
    get_target_property(own ${target} PRECOMPILE_HEADERS)
    if(reused OR own)
      continue()  # the tests' header, or one of its own
    endif()
    get_target_property(options ${target} COMPILE_OPTIONS)
    get_target_property(pic ${target} POSITION_INDEPENDENT_CODE)
    get_target_property(type ${target} TYPE)
    if(type STREQUAL "SHARED_LIBRARY")  # CMake compiles those with -fPIC unasked
      set(pic ON)
    endif()
    if(NOT pic)
      set(pic OFF)
    endif()
    string(SHA1 key "${pic} ${options}")
    string(SUBSTRING "${key}" 0 8 key)
    set(owner rsu_pch_${key})
    if(NOT TARGET ${owner})
      add_library(${owner} OBJECT ${PROJECT_SOURCE_DIR}/cmake/precompiled_header_owner.cpp)
      target_link_libraries(${owner} PRIVATE Eigen3::Eigen)
      target_compile_options(${owner} PRIVATE ${options})
      set_target_properties(${owner} PROPERTIES POSITION_INDEPENDENT_CODE ${pic})
      target_precompile_headers(${owner} PRIVATE ${RSU_PRECOMPILED_HEADERS})
      list(APPEND owners ${owner})
    endif()
    target_precompile_headers(${target} REUSE_FROM ${owner})
    math(EXPR users "${users} + 1")
  endforeach()
  list(LENGTH owners count)
  message(STATUS "Shared precompiled headers: ${count}, reused by ${users} targets")
endfunction()
