// libFuzzer target: the rplidar decoder on arbitrary bytes (fuzz/fuzz_common.hpp).
#include "drivers/protocols/rplidar.hpp"
#include "fuzz/fuzz_common.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  sweepmap::fuzzDecoder<sweepmap::rplidar::Decoder, sweepmap::rplidar::Event>(data, size);
  return 0;
}
