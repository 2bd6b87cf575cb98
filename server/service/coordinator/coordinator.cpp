#include "service/coordinator/coordinator.h"

#include <memory>

#include "service/coordinator/sharded_run.h"

namespace luxel::service::coordinator {

Coordinator::Coordinator(BakeStore& bakes, CoordinatorOptions options)
    : bakes_(bakes),
      options_(std::move(options)),
      pool_(std::make_unique<WorkerPool>(options_.workers)) {}

Coordinator::~Coordinator() = default;

Result<pipeline::BakeResult> Coordinator::run(const ShardedJob& job) {
  Run run(bakes_, *pool_, options_, job);
  return run.execute();
}

}  // namespace luxel::service::coordinator
