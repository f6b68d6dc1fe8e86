#include "combabc/core/executor.hpp"

#include <algorithm>

namespace combabc {

void ThreadPoolExecutor::Execute(std::size_t n, BatchTask& task) {
  // Enough chunks per thread to balance uneven simulators, few enough to amortise the handoff.
  const std::size_t chunk =
      std::max<std::size_t>(1, n / (static_cast<std::size_t>(pool_.size()) * 4));
  pool_.ParallelFor(
      n, chunk, [&task](std::size_t begin, std::size_t end) { task.EvaluateRange(begin, end); });
}

}  // namespace combabc
