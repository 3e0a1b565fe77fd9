// libFuzzer target: message validation against the .lcm schema (core/lcm_schema.hpp), the
// check every node's input passes before any field is read, on arbitrary bytes. The first
// byte picks a known type whose fingerprint the input then starts with, so the fuzzer reaches
// past the fingerprint into every type's members. Checked: validate never crashes, and
// whatever it accepts the bounded decoder reads to the last byte. abort() on a violation.
#include <cstdlib>
#include <vector>

#include "core/lcm_schema.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using sweepmap::LcmSchema;
  if (size == 0) return 0;
  const LcmSchema& schema = LcmSchema::builtIn();
  const auto& types = schema.structs();
  const int64_t fingerprint = types[data[0] % types.size()].fingerprint;
  std::vector<uint8_t> message(8);
  for (int k = 0; k < 8; ++k) message[k] = static_cast<uint8_t>(fingerprint >> (56 - 8 * k));
  message.insert(message.end(), data + 1, data + size);
  const std::vector<uint8_t> raw(data, data + size);
  for (const std::vector<uint8_t>* m : {static_cast<const std::vector<uint8_t>*>(&message), &raw}) {
    if (!schema.validate(m->data(), m->size()).empty()) continue;
    sweepmap::LcmValue value;
    try {
      if (!schema.decode(m->data(), m->size(), &value)) std::abort();
    } catch (const sweepmap::LcmSchemaError&) {
      std::abort();  // valid, yet the decoder refuses it
    }
  }
  return 0;
}
