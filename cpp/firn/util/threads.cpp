#include "firn/util/threads.h"

#include <memory>
#include <mutex>

#include <tbb/global_control.h>
#include <tbb/info.h>

#include "firn/util/error.h"

namespace firn {

namespace {
std::mutex gMutex;
std::unique_ptr<tbb::global_control> gLimit;  // alive while a cap is set
}  // namespace

void setThreadCount(int count) {
    if (count < 0) throw InvalidArgument("thread count must be 0 (all cores) or positive");
    std::lock_guard<std::mutex> lock(gMutex);
    gLimit.reset();
    if (count > 0)
        gLimit = std::make_unique<tbb::global_control>(tbb::global_control::max_allowed_parallelism,
                                                       static_cast<std::size_t>(count));
}

int hardwareThreadCount() { return tbb::info::default_concurrency(); }

}  // namespace firn
