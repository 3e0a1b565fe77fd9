// libFuzzer target: the ydlidar decoder on arbitrary bytes (fuzz/fuzz_common.hpp).
#include "drivers/protocols/ydlidar.hpp"
#include "fuzz/fuzz_common.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  sweepmap::fuzzDecoder<sweepmap::ydlidar::Decoder, sweepmap::ydlidar::Event>(data, size);
  return 0;
}
