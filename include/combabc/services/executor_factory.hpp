#pragma once
// Where a service's simulations run (run, resume, enumerate).
#include <functional>
#include <memory>

#include "combabc/core/executor.hpp"

namespace combabc::services {

// Where the simulations run, made once the run's threads are known (the config's [sampler] threads
// or the override). Empty: a ThreadPoolExecutor. With a distributed executor (MPI) every worker
// calls the same service; only the executor's primary writes files, and every worker returns or
// throws alike (Executor::Join), so that all exit with the same code.
using ExecutorFactory = std::function<std::unique_ptr<Executor>(int threads)>;

}  // namespace combabc::services
