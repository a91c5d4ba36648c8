#pragma once
// How the multi-threaded paths (ψ, the batch searches) share their work among threads.

#include <algorithm>
#include <cstddef>
#include <exception>
#include <system_error>
#include <thread>
#include <vector>

namespace pcl {
namespace fot {
namespace detail {

/**
 * Workers for `pieces` pieces of work when `requested` threads are asked for (0: every hardware thread): at
 * least one, at most one per piece and four per hardware thread. Each worker holds its own buffers, so an
 * unbounded request must not become unbounded memory.
 */
inline std::size_t workerCount(unsigned requested, std::size_t pieces) {
  if (requested == 1 || pieces <= 1) return 1;
  static const std::size_t hardware = std::max(1u, std::thread::hardware_concurrency());  // reads /sys
  const std::size_t wanted = requested ? std::min<std::size_t>(requested, 4 * hardware) : hardware;
  return std::max<std::size_t>(1, std::min(wanted, pieces));
}

/**
 * Runs work(w) for every w in [0, workers): share 0 in the calling thread, the others in threads of their
 * own. A share whose thread the system cannot start runs in the calling thread instead. The first exception
 * a share throws reaches the caller once every thread has finished.
 */
template <typename Work>
void runWorkers(std::size_t workers, Work&& work) {
  std::vector<std::exception_ptr> errors(workers);
  auto guarded = [&](std::size_t w) {
    try {
      work(w);
    } catch (...) {
      errors[w] = std::current_exception();
    }
  };
  std::vector<std::thread> pool;
  pool.reserve(workers);
  std::size_t started = 1;
  try {
    for (; started < workers; ++started) pool.emplace_back(guarded, started);
  } catch (const std::system_error&) {  // out of threads: the caller takes the rest
  }
  guarded(0);
  for (std::size_t w = started; w < workers; ++w) guarded(w);
  for (auto& t : pool) t.join();
  for (const auto& e : errors)
    if (e) std::rethrow_exception(e);
}

}  // namespace detail
}  // namespace fot
}  // namespace pcl
