// The core's long work runs in its own TBB arena: TBB's workers run its tasks at a lower OS priority, so the
// host's UI thread is not starved of the processor (the cause of a UI that froze for a whole bake on a busy
// machine), and its thread cap never limits the host.
#include "firn/util/threads.h"

#include <atomic>
#include <map>
#include <mutex>
#include <stdexcept>
#include <thread>

#include <gtest/gtest.h>
#include <sys/resource.h>
#include <sys/syscall.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <unistd.h>

#include "firn/util/error.h"

namespace firn {

namespace {
int niceness() { return getpriority(PRIO_PROCESS, static_cast<id_t>(syscall(SYS_gettid))); }
}  // namespace

TEST(Threads, WorkersRunTheCoresTasksAtLowerPriorityAndTheCallerKeepsItsOwn) {
    ASSERT_GE(hardwareThreadCount(), 2) << "needs a TBB worker beside the calling thread";
    setThreadCount(2);
    const std::thread::id caller = std::this_thread::get_id();
    const int callerNiceness = niceness();
    std::mutex mutex;
    std::map<std::thread::id, int> nicenessByThread;
    std::atomic<bool> workerSeen{false};
    runInCoreArena([&] {
        // Chunks wait until a worker has joined, so one does take part whatever the machine's load.
        tbb::parallel_for(tbb::blocked_range<int>(0, 64, 1), [&](const tbb::blocked_range<int> &) {
            {
                std::lock_guard<std::mutex> lock(mutex);
                nicenessByThread[std::this_thread::get_id()] = niceness();
            }
            if (std::this_thread::get_id() != caller) workerSeen = true;
            while (!workerSeen) std::this_thread::yield();
        });
    });
    setThreadCount(0);

    ASSERT_GE(nicenessByThread.size(), 2u);
    for (const auto &[thread, value] : nicenessByThread) {
        if (thread == caller)
            EXPECT_EQ(value, callerNiceness) << "the calling thread's priority is its owner's to set";
        else
            EXPECT_GE(value, kWorkerNiceness) << "a worker ran the core's task at the host's priority";
    }
    EXPECT_EQ(niceness(), callerNiceness);
}

TEST(Threads, ThreadCountCapsTheCoresArenaOnly) {
    setThreadCount(1);
    EXPECT_EQ(runInCoreArena([] { return tbb::this_task_arena::max_concurrency(); }), 1);
    EXPECT_EQ(tbb::this_task_arena::max_concurrency(), hardwareThreadCount());  // the host keeps every thread
    setThreadCount(0);
    EXPECT_EQ(runInCoreArena([] { return tbb::this_task_arena::max_concurrency(); }), hardwareThreadCount());
    EXPECT_THROW(setThreadCount(-1), InvalidArgument);
}

// shelterTargets builds the shelter while the open surfaces' turns are found beside it: when both throw (out of
// memory, say), the shelter's error is the one reported, not the task's that tbb::task_group::wait rethrows.
TEST(Threads, WhenBothThrowTheWorksExceptionGoesOnAndTheSideTaskHasEnded) {
    std::atomic<bool> sideEnded{false};
    try {
        runBeside(
            [&] {
                sideEnded = true;
                throw std::runtime_error("side");
            },
            [] { throw InvalidArgument("work"); });
        FAIL() << "nothing thrown";
    } catch (const InvalidArgument &error) {
        EXPECT_STREQ(error.what(), "work");
    } catch (const std::runtime_error &error) {
        FAIL() << "the side task's exception replaced the work's: " << error.what();
    }
    EXPECT_TRUE(sideEnded);
}

TEST(Threads, TheSideTasksExceptionGoesOnWhenTheWorkSucceeds) {
    bool worked = false;
    EXPECT_THROW(runBeside([] { throw std::runtime_error("side"); }, [&] { worked = true; }), std::runtime_error);
    EXPECT_TRUE(worked);
}

}  // namespace firn
