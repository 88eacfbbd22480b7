#pragma once
// Reads a tool's CSV output (a header line, then comma-separated values) so the tests can check the
// values of named columns rather than the file's existence.
#include <gtest/gtest.h>

#include <cstddef>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

namespace occ_improve::test {

struct CsvTable {
  std::vector<std::string> header;
  std::vector<std::vector<std::string>> rows;

  /// Index of a column; fails the test (and returns the header's size) when it is missing.
  std::size_t index(const std::string& name) const {
    for (std::size_t i = 0; i < header.size(); ++i)
      if (header[i] == name) return i;
    ADD_FAILURE() << "no column '" << name << "'";
    return header.size();
  }
  /// The numbers of one column, in row order.
  std::vector<double> column(const std::string& name) const {
    const std::size_t i = index(name);
    std::vector<double> values;
    for (const auto& row : rows) values.push_back(i < row.size() ? std::stod(row[i]) : 0.0);
    return values;
  }
  double value(std::size_t row, const std::string& name) const {
    const std::size_t i = index(name);
    return i < rows[row].size() ? std::stod(rows[row][i]) : 0.0;
  }
};

inline std::vector<std::string> split_csv_line(const std::string& line) {
  std::vector<std::string> fields;
  std::istringstream in(line);
  std::string field;
  while (std::getline(in, field, ',')) fields.push_back(field);
  return fields;
}

inline CsvTable read_csv(const std::filesystem::path& path) {
  CsvTable table;
  std::ifstream in(path);
  std::string line;
  if (!std::getline(in, line)) {
    ADD_FAILURE() << "cannot read '" << path.string() << "'";
    return table;
  }
  table.header = split_csv_line(line);
  while (std::getline(in, line))
    if (!line.empty()) table.rows.push_back(split_csv_line(line));
  return table;
}

}  // namespace occ_improve::test
