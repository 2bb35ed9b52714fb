#pragma once

#include <memory>
#include <utility>

#include <tbb/task_arena.h>

namespace firn {

// The core's own TBB arena, for long work called from a host that shares TBB with Firn (Blender does; the
// Python bindings run every long call through runInCoreArena). Its thread cap applies to it alone, never to
// the host's own parallel work; its priority is low, so the host's parallel work gets TBB's workers first;
// and the workers run its tasks at a lower OS priority (niceness kWorkerNiceness), so the host's UI thread is
// never starved of the processor by a bake running on every core.

constexpr int kWorkerNiceness = 5;

// Caps the threads the core's parallel loops use; 0 lifts the cap (all hardware threads).
void setThreadCount(int count);
int hardwareThreadCount();

// The arena the core's work runs in (replaced, not changed, when the thread count changes).
std::shared_ptr<tbb::task_arena> coreArena();

// Runs `work` on the calling thread inside the core's arena; its parallel loops use the arena's threads.
template <class Work>
auto runInCoreArena(Work &&work) -> decltype(work()) {
    const std::shared_ptr<tbb::task_arena> arena = coreArena();  // alive until the work is done
    return arena->execute(std::forward<Work>(work));
}

}  // namespace firn
