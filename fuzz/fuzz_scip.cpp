// libFuzzer target: the scip decoder on arbitrary bytes (fuzz/fuzz_common.hpp).
#include "drivers/protocols/scip.hpp"
#include "fuzz/fuzz_common.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  sweepmap::fuzzDecoder<sweepmap::scip::Decoder, sweepmap::scip::Event>(data, size);
  return 0;
}
