// libFuzzer target: CSV text -> parse_csv, parse_csv_number of every cell (fuzz_entries.hpp).
#include <cstdio>
#include <cstdlib>
#include <exception>

#include "fuzz_entries.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  try {
    ricochet::fuzz::csv_entry(ricochet::fuzz::as_text(data, size));
  } catch (const std::exception& e) {  // InputError is caught inside: this is a finding
    std::fprintf(stderr, "fuzz_csv: uncaught exception: %s\n", e.what());
    std::abort();
  }
  return 0;
}
