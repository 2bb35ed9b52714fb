#include "firn/util/work_check.h"

#include <atomic>
#include <cstdint>

#include <gtest/gtest.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include "firn/util/error.h"

namespace firn {

TEST(WorkCheck, ChecksWhenMadeAndAtEveryKUnits) {
    Progress progress;
    const SubProgress step(&progress, 0.0, 1.0);
    WorkCheck work(step);
    progress.cancel();
    work.add(WorkCheck::kUnits - 1);  // the count short of kUnits: no check yet
    EXPECT_THROW(work.add(1), Cancelled);
    EXPECT_THROW(WorkCheck{step}, Cancelled);  // made after the cancel
}

TEST(WorkCheck, CountStartsAgainAfterEachCheck) {
    Progress progress;
    WorkCheck work(SubProgress(&progress, 0.0, 1.0));
    work.add(WorkCheck::kUnits + 5);  // a check (not cancelled), the count back to 0
    progress.cancel();
    work.add(WorkCheck::kUnits - 1);
    EXPECT_THROW(work.add(1), Cancelled);
}

TEST(WorkCheck, WithoutProgressNeverThrows) {
    WorkCheck work(SubProgress(nullptr, 0.0, 1.0));
    EXPECT_NO_THROW(work.add(10 * WorkCheck::kUnits));
}

// In a TBB loop whose chunks the auto partitioner makes as large as it likes: once cancelled, each thread stops
// within kUnits of work (its chunk's WorkCheck), and no chunk starts after it (each checks when made), so the work
// done after the cancel is at most the threads' kUnits each.
TEST(WorkCheck, StopsATbbLoopWithinKUnitsPerThread) {
    constexpr std::uint64_t kItems = 1u << 26, kCancelAt = 1u << 20;
    Progress progress;
    const SubProgress step(&progress, 0.0, 1.0);
    std::atomic<std::uint64_t> done{0};
    EXPECT_THROW(tbb::parallel_for(tbb::blocked_range<std::uint64_t>(0, kItems, 1024),
                                   [&](const auto &range) {
                                       WorkCheck work(step);
                                       for (std::uint64_t i = range.begin(); i != range.end(); ++i) {
                                           work.add();
                                           if (++done == kCancelAt) progress.cancel();
                                       }
                                   }),
                 Cancelled);
    EXPECT_LE(done.load(), kCancelAt + std::uint64_t(tbb::this_task_arena::max_concurrency()) * WorkCheck::kUnits);
}

}  // namespace firn
