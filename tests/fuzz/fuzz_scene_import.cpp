// libFuzzer target: scene_import (see fuzz_targets.h for the contract and README "Fuzzing").
#include "fuzz_targets.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  return raylab::fuzz::scene_import(data, size);
}
