# SPDX-License-Identifier: Apache-2.0
# Sanitizers for every target (configure Debug or RelWithDebInfo). Errors abort so that CTest reports
# them as failures.
#   RSU_SANITIZE=ON         AddressSanitizer + UndefinedBehaviorSanitizer (build-asan/)
#   RSU_SANITIZE_THREAD=ON  ThreadSanitizer (build-tsan/); cannot be combined with ASan
if(RSU_SANITIZE AND RSU_SANITIZE_THREAD)
  message(FATAL_ERROR "RSU_SANITIZE (ASan) and RSU_SANITIZE_THREAD (TSan) cannot be combined")
endif()
if(RSU_SANITIZE)
  add_compile_options(-fsanitize=address,undefined -fno-omit-frame-pointer -fno-sanitize-recover=all)
  add_link_options(-fsanitize=address,undefined)
  # Third-party headers without UBSan (their ASan instrumentation stays): cmake/ubsan_ignorelist.txt says
  # why and what it saves. GCC has no such list; the ASan tree is clang's (scripts/build.sh).
  if(CMAKE_CXX_COMPILER_ID STREQUAL "Clang")
    add_compile_options(-fsanitize-ignorelist=${CMAKE_CURRENT_LIST_DIR}/ubsan_ignorelist.txt)
  endif()
  # Eigen 3.4 stops trusting malloc's 16-byte alignment when it sees __SANITIZE_ADDRESS__ and then frees
  # its heap blocks with its own "handmade" scheme, while the prebuilt (uninstrumented) PCL allocates
  # them with plain malloc: a PCL object built there and freed in our code (NDT's voxel leaves) is a
  # heap-buffer-overflow under ASan only. glibc's malloc (and ASan's) do return 16-byte-aligned blocks on
  # x86-64, so tell Eigen so and keep the same scheme as the libraries we link.
  add_compile_definitions(EIGEN_MALLOC_ALREADY_ALIGNED=1)
endif()
if(RSU_SANITIZE_THREAD)
  # Only our code is instrumented; reports inside the prebuilt libraries are suppressed one by one in
  # tests/tsan.supp (scripts/test.sh passes it in TSAN_OPTIONS).
  add_compile_options(-fsanitize=thread -fno-omit-frame-pointer)
  add_link_options(-fsanitize=thread)
  # TSan does not model std::atomic_thread_fence (GCC refuses it under -Werror=tsan). Boost.Asio fences
  # around handler invocation only to order memory its scheduler already orders with its mutex, which
  # TSan does see: with the fence left out TSan checks the real synchronisation, not a blind spot.
  add_compile_definitions(BOOST_ASIO_DISABLE_FENCED_BLOCK)
endif()
