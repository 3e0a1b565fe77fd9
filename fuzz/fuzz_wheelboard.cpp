// libFuzzer target: the wheel board protocol decoder on arbitrary bytes (fuzz/fuzz_common.hpp).
#include "drivers/protocols/wheelboard.hpp"
#include "fuzz/fuzz_common.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  sweepmap::fuzzDecoder<sweepmap::wheelboard::Decoder, sweepmap::wheelboard::Event>(data, size);
  return 0;
}
