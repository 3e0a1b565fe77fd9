// Runs a libFuzzer target's LLVMFuzzerTestOneInput over saved inputs (files or folders of
// files, in name order) without libFuzzer: the corpus as a regression test in every build.
// A crash or a sanitizer report fails the test; so does an empty corpus.
#include <algorithm>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <iterator>
#include <string>
#include <vector>

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size);

int main(int argc, char** argv) {
  namespace fs = std::filesystem;
  std::vector<fs::path> files;
  for (int i = 1; i < argc; ++i) {
    const fs::path p = argv[i];
    if (fs::is_directory(p)) {
      for (const auto& e : fs::directory_iterator(p)) {
        if (e.is_regular_file()) files.push_back(e.path());
      }
    } else if (fs::is_regular_file(p)) {
      files.push_back(p);
    } else {
      std::cerr << "fuzz replay: " << p << ": no such file or folder\n";
      return 2;
    }
  }
  std::sort(files.begin(), files.end());
  if (files.empty()) {
    std::cerr << "fuzz replay: no inputs\n";
    return 2;
  }
  size_t bytes = 0;
  for (const fs::path& f : files) {
    std::ifstream in(f, std::ios::binary);
    const std::vector<uint8_t> data{std::istreambuf_iterator<char>(in),
                                    std::istreambuf_iterator<char>()};
    bytes += data.size();
    LLVMFuzzerTestOneInput(data.data(), data.size());
  }
  std::cout << "fuzz replay: " << files.size() << " inputs, " << bytes << " bytes, no crash\n";
  return 0;
}
