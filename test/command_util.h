// Helpers for tests that run the package's tools, scripts and launch files as a user would (through a
// shell) and for tests that edit a copy of the package's config. ROS-free: unit and ROS tests share it.
#pragma once

#include <gtest/gtest.h>
#include <sys/wait.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <cmath>
#include <cstdlib>
#include <iterator>
#include <map>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

namespace go_feap::test {

/// Runs `command` through the shell and returns its exit status (128 + the signal for one killed by a
/// signal, -1 when it could not be started) and what it wrote to stdout and stderr together.
inline std::pair<int, std::string> runCommand(const std::string& command) {
  std::string output;
  FILE* pipe = popen((command + " 2>&1").c_str(), "r");
  if (!pipe) return {-1, "popen failed: " + command};
  char buffer[4096];
  while (std::fgets(buffer, sizeof(buffer), pipe)) output += buffer;
  const int status = pclose(pipe);
  if (status == -1) return {-1, output};
  return {WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status), output};
}

/// The whole text of a file ("" when it cannot be read).
inline std::string readText(const std::filesystem::path& file) {
  std::ifstream in(file);
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

/// A CSV file of numbers with a header line: one map from column name to value per row. A cell that is no
/// number is NaN (a test then fails on it rather than reading 0).
inline std::vector<std::map<std::string, double>> readCsv(const std::filesystem::path& file) {
  std::ifstream in(file);
  std::string line;
  std::vector<std::string> names;
  if (std::getline(in, line)) {
    std::istringstream header(line);
    for (std::string name; std::getline(header, name, ',');) names.push_back(name);
  }
  std::vector<std::map<std::string, double>> rows;
  while (std::getline(in, line)) {
    if (line.empty()) continue;
    std::istringstream cells(line);
    std::map<std::string, double> row;
    std::string cell;
    for (const std::string& name : names) {
      if (!std::getline(cells, cell, ',')) cell.clear();
      char* end = nullptr;
      const double v = std::strtod(cell.c_str(), &end);
      row[name] = !cell.empty() && end == cell.c_str() + cell.size() ? v : std::nan("");
    }
    rows.push_back(std::move(row));
  }
  return rows;
}

/// Replaces `from` by `to` in `file`, where `from` must occur exactly once (a test editing a config value
/// that is not there, or is there twice, would otherwise test nothing). Use as
/// ASSERT_TRUE(replaceOnce(file, from, to)).
inline ::testing::AssertionResult replaceOnce(const std::filesystem::path& file, const std::string& from,
                                              const std::string& to) {
  std::string text = readText(file);
  const std::size_t at = text.find(from);
  if (at == std::string::npos) return ::testing::AssertionFailure() << file << ": no '" << from << "'";
  if (text.find(from, at + 1) != std::string::npos)
    return ::testing::AssertionFailure() << file << ": '" << from << "' more than once";
  std::ofstream(file) << text.replace(at, from.size(), to);
  return ::testing::AssertionSuccess();
}

}  // namespace go_feap::test
