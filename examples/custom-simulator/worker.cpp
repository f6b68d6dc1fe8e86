// The example worker of worker.py in C++ (protocol combabc-worker 2, docs/simulators.md): a
// handshake line, then one answer line per request line, starting with the request's id. Standard
// library only; nothing but protocol lines may go to stdout (diagnostics go to stderr).
#include <cmath>
#include <cstdio>
#include <iostream>
#include <sstream>
#include <string>
#include <vector>

namespace {

constexpr int kOutputs = 21;  // the config's [simulator.outputs]: 0, 0.03, ..., 0.60 m
constexpr int kSupports = 6;  // one per bit (1 = fixed)

std::vector<double> Simulate(const std::string& bits) {
  std::vector<double> y(kOutputs, 0.05);
  for (int j = 0; j < kOutputs; ++j) {
    const double x = 0.03 * j;
    for (int k = 0; k < kSupports; ++k) {
      const double c = 0.05 + 0.1 * k;
      if (bits[static_cast<std::size_t>(k)] == '0') y[j] += std::exp(-std::pow((x - c) / 0.06, 2));
    }
  }
  return y;
}

}  // namespace

int main() {
  std::cout << "combabc-worker 2 " << kOutputs << " example-supports-cpp 1.0" << std::endl;
  std::string line;
  while (std::getline(std::cin, line)) {
    std::istringstream request(line);
    std::string id;
    std::string bits;
    request >> id >> bits;  // the reals follow; this model has none
    if (bits.size() != static_cast<std::size_t>(kSupports)) {
      std::cout << id << " error expected " << kSupports << " bits, got " << bits.size()
                << std::endl;
      continue;
    }
    std::cout << id << " ok";
    for (double v : Simulate(bits)) {
      char text[32];
      std::snprintf(text, sizeof text, " %.17g", v);  // exact round trip
      std::cout << text;
    }
    std::cout << std::endl;  // flush: combabc waits for the whole line
  }
  return 0;
}
