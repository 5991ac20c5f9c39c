// SPDX-License-Identifier: Apache-2.0
// The sanitizer trees' proof that their sanitizers fire where the project needs them, now that
// cmake/ubsan_ignorelist.txt leaves UBSan out of the third-party headers and both trees share precompiled
// headers (cmake/precompiled_headers.cmake). Each mode commits one error; its test
// (tests/structure/CMakeLists.txt) passes only if the sanitizer reports it.
//   signed-overflow: a signed integer overflow in our code (UBSan).
//   misaligned-load: a 4-byte load from an odd address in our code, as a careless parser would (UBSan).
//   overflow-in-std: a heap read past a vector's end inside libstdc++'s std::accumulate (ASan, a header).
//   data-race:       two threads add to one counter without synchronisation (TSan).
// The operands come from the command line, so that no compiler can fold the error away.
#include <cstdint>
#include <cstdio>
#include <numeric>
#include <string_view>
#include <thread>
#include <vector>

namespace {

int signed_overflow(int addend) {
  int total = 2147483647;
  total += addend;
  return total;
}

std::uint32_t misaligned_load(std::size_t offset) {
  alignas(8) static std::uint8_t bytes[16] = {1, 2, 3, 4, 5, 6, 7, 8};
  const auto* word = static_cast<const std::uint32_t*>(static_cast<const void*>(bytes + offset));
  return *word;
}

int overflow_in_std(std::size_t extra) {
  const std::vector<int> values(4, 1);
  return std::accumulate(values.begin(), values.begin() + 4 + static_cast<std::ptrdiff_t>(extra), 0);
}

int data_race(std::size_t rounds) {
  int counter = 0;
  const auto add = [&counter, rounds] {
    for (std::size_t i = 0; i < rounds; ++i) {
      ++counter;
    }
  };
  std::thread other(add);
  add();
  other.join();
  return counter;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr,
                 "usage: sanitizer_canary signed-overflow|misaligned-load|overflow-in-std|data-race\n");
    return 2;
  }
  const std::string_view mode = argv[1];
  // argc is 2: every operand below is 1, known only at run time.
  const auto one = static_cast<std::size_t>(argc - 1);
  long long result = 0;
  if (mode == "signed-overflow") {
    result = signed_overflow(static_cast<int>(one));
  } else if (mode == "misaligned-load") {
    result = misaligned_load(one);
  } else if (mode == "overflow-in-std") {
    result = overflow_in_std(one);
  } else if (mode == "data-race") {
    result = data_race(1000 * one);
  } else {
    std::fprintf(stderr, "unknown mode %s\n", argv[1]);
    return 2;
  }
  std::printf("NOT REPORTED: %s ran to the end (result %lld)\n", argv[1], result);
  return 0;
}
