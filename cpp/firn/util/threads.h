#pragma once

namespace firn {

// Caps the threads every parallel loop of the core may use; 0 lifts the cap (all hardware threads).
void setThreadCount(int count);
int hardwareThreadCount();

}  // namespace firn
