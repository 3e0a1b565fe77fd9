// The figures of an evaluation report: each is drawn by a callback into the report's
// directory; a figure that cannot be drawn (no gnuplot, bad data) is reported on stderr and
// listed in errors(), and never fails the evaluation.
#pragma once

#include <filesystem>
#include <functional>
#include <iostream>
#include <string>
#include <vector>

namespace sweepmap {

class Figures {
 public:
  Figures(std::filesystem::path dir, bool enabled) : dir_(std::move(dir)), enabled_(enabled) {}
  // Draws with `draw(path)`; on success records the figure (file and caption) for the report.
  void add(const std::string& file, const std::string& caption,
           const std::function<void(const std::string&)>& draw) {
    if (!enabled_) return;
    try {
      draw((dir_ / file).string());
      files_.push_back({file, caption});
    } catch (const std::exception& e) {
      errors_.push_back(file + ": " + e.what());
      std::cerr << "eval: figure " << file << " not drawn: " << e.what() << "\n";
    }
  }
  struct Entry {
    std::string file, caption;
  };
  const std::vector<Entry>& files() const { return files_; }
  const std::vector<std::string>& errors() const { return errors_; }

 private:
  std::filesystem::path dir_;
  bool enabled_;
  std::vector<Entry> files_;
  std::vector<std::string> errors_;
};

}  // namespace sweepmap
