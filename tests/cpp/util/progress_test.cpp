#include "firn/util/progress.h"

#include <thread>
#include <vector>

#include <gtest/gtest.h>

#include "firn/util/error.h"

namespace firn {

TEST(Progress, ClampsAndKeepsStage) {
    Progress progress;
    progress.report(0.25, "sampling");
    EXPECT_DOUBLE_EQ(progress.fraction(), 0.25);
    EXPECT_EQ(progress.stage(), "sampling");
    progress.report(7.0);
    EXPECT_DOUBLE_EQ(progress.fraction(), 1.0);
    EXPECT_EQ(progress.stage(), "sampling");
}

TEST(Progress, CancelMakesWorkThrow) {
    Progress progress;
    EXPECT_NO_THROW(progress.throwIfCancelled());
    progress.cancel();
    EXPECT_THROW(progress.throwIfCancelled(), Cancelled);
}

TEST(Progress, CallbackSeesFinalReportFromAnyThread) {
    std::vector<double> seen;
    std::mutex m;
    Progress progress([&](double f, const std::string &) {
        std::lock_guard<std::mutex> lock(m);
        seen.push_back(f);
    });
    std::thread worker([&] {
        for (int i = 0; i <= 1000; ++i) progress.report(i / 1000.0);
    });
    worker.join();
    ASSERT_FALSE(seen.empty());
    EXPECT_DOUBLE_EQ(seen.back(), 1.0);  // the end is always reported
    EXPECT_LT(seen.size(), 1001u);       // throttled
}

TEST(SubProgress, MapsOntoParentRange) {
    Progress progress;
    SubProgress(&progress, 0.5, 0.75).report(0.5);
    EXPECT_DOUBLE_EQ(progress.fraction(), 0.625);
}

// A new stage always reaches the callback, however soon after the last (a watcher that acts on a stage, as a
// test that cancels there, sees it).
TEST(Progress, CallbackSeesEveryNewStage) {
    std::vector<std::string> stages;
    Progress progress([&](double, const std::string &stage) { stages.push_back(stage); });
    progress.report(0.1, "first");
    progress.report(0.2);  // throttled: within 0.1 s of the last
    progress.report(0.3, "second");
    EXPECT_EQ(stages, (std::vector<std::string>{"first", "second"}));
}

// Steps side by side (bake: thin snow traced beside the light) move the parent by their shares of its range; a
// step's fraction going back (its loop's reports out of order) moves nothing back; both stop when cancelled.
TEST(SideBySideProgress, SharesAddAndNeverGoBack) {
    Progress progress;
    const SideBySideProgress beside(&progress, 0.2, 0.6, {0.5, 0.5});
    const SubProgress light = beside.step(0), trace = beside.step(1);
    trace.report(0.5);
    EXPECT_DOUBLE_EQ(progress.fraction(), 0.3);  // 0.2 + 0.4 * (0.5 * 0.5)
    light.report(1.0);
    EXPECT_DOUBLE_EQ(progress.fraction(), 0.5);
    trace.report(0.25);  // reported late
    EXPECT_DOUBLE_EQ(progress.fraction(), 0.5);
    trace.report(1.0);
    EXPECT_DOUBLE_EQ(progress.fraction(), 0.6);
    EXPECT_NO_THROW(light.throwIfCancelled());
    progress.cancel();
    EXPECT_THROW(light.throwIfCancelled(), Cancelled);
    EXPECT_THROW(trace.throwIfCancelled(), Cancelled);
}

// Two threads reporting at once, each its steps in order: the fraction the callbacks see never goes back, and the
// end is reached.
TEST(SideBySideProgress, CallbacksNeverGoBackUnderTwoReporters) {
    std::vector<double> seen;
    Progress progress([&](double f, const std::string &) { seen.push_back(f); }, 0.0);  // called back from either
    const SideBySideProgress beside(&progress, 0.0, 1.0, {0.25, 0.75});
    auto run = [&](std::size_t step) {
        for (int i = 0; i <= 20000; ++i) beside.step(step).report(i / 20000.0);
    };
    std::thread other(run, 0);
    run(1);
    other.join();
    ASSERT_FALSE(seen.empty());
    for (std::size_t i = 1; i < seen.size(); ++i) ASSERT_GE(seen[i], seen[i - 1]) << i;
    EXPECT_DOUBLE_EQ(progress.fraction(), 1.0);
}

}  // namespace firn
