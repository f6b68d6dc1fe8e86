// libFuzzer target: the TOML configuration reader, combabc::ParseConfig, on arbitrary bytes.
// A combabc::Error is the expected outcome for bad input; anything else is a finding (see
// fuzz_util.hpp). Seeds: fuzz/corpus/config/; dictionary: fuzz/config.dict.
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "combabc/config/config.hpp"
#include "combabc/core/error.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  try {
    // A path with a directory, as LoadConfig passes: data.csv is resolved against it (not read).
    const combabc::CalibrationConfig config = combabc::ParseConfig(text, "fuzz/config.toml");
    (void)config;
  } catch (const combabc::Error&) {
    // Expected: the input is not a valid configuration.
  }
  return 0;
}
