// libFuzzer entry of one target; TRAJ_FUZZ_ENTRY names the function of fuzz_entries.hpp.
#include "fuzz_entries.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, std::size_t size) {
  return traj::fuzz::TRAJ_FUZZ_ENTRY(data, size);
}
