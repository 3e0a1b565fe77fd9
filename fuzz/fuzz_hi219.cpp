// libFuzzer target: the HI219 IMU decoder on arbitrary bytes (fuzz/fuzz_common.hpp).
#include "drivers/protocols/hi219.hpp"
#include "fuzz/fuzz_common.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  sweepmap::fuzzDecoder<sweepmap::hi219::Decoder, sweepmap::hi219::Event>(data, size);
  return 0;
}
