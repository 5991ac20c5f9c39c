// SPDX-License-Identifier: Apache-2.0
// The one source of each object library that owns a precompiled header (cmake/precompiled_headers.cmake,
// tests/CMakeLists.txt): CMake builds a target's precompiled header only if it has a source to compile.
