// SPDX-License-Identifier: Apache-2.0
// rsu_test_pch owns the precompiled header every test binary reuses (tests/CMakeLists.txt); a target
// needs a source of its own to be built, and this is it.
