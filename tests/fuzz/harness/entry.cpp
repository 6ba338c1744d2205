// libFuzzer's entry point for one target: compiled once per target with
// -DLASERCELL_FUZZ_NAME=<name> (tests/fuzz/CMakeLists.txt, LASERCELL_FUZZ builds only).
#include <cstddef>
#include <cstdint>

#define LASERCELL_FUZZ_CONCAT_(a, b) a##b
#define LASERCELL_FUZZ_CONCAT(a, b) LASERCELL_FUZZ_CONCAT_(a, b)
#define LASERCELL_FUZZ_FUNCTION LASERCELL_FUZZ_CONCAT(lasercell_fuzz_, LASERCELL_FUZZ_NAME)

extern "C" int LASERCELL_FUZZ_FUNCTION(const std::uint8_t* data, std::size_t size);

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  return LASERCELL_FUZZ_FUNCTION(data, size);
}
