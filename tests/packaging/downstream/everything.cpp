// Links combabc::combabc from the installed package: reading a CSV reaches the calibration
// component and libcsv, which a static install must bring along.
#include <cstdio>

#include "combabc/data/csv_reader.hpp"

int main() {
  combabc::CsvReader reader("position,value\n0.5,1e-6\n", "inline.csv");
  const auto& header = reader.ReadHeader();
  const bool read = reader.Next() && reader.cells().size() == 2 && reader.cells()[1] == "1e-6";
  std::printf("%s %s %s\n", header[0].c_str(), header[1].c_str(), read ? "read" : "not read");
  return read && header.size() == 2 ? 0 : 1;
}
