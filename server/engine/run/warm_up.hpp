// What an engine does once as it starts: every pass built and launched once in its first
// workspace, so no request pays for a compile, and a CPU device's worker threads niced.
#pragma once

#include <sys/types.h>

#include <set>

#include "engine/run/workspace.hpp"

namespace shadow {

// Renders a one-triangle scene through every pass: each product, filter, CSM storage, a cube, PSM
// and an atlas.
void warm_up(Workspace& workspace);

// The process' threads now (Linux: /proc/self/task), to tell the ones the device starts.
std::set<pid_t> thread_ids();

// A CPU device's worker threads (PoCL's, started while the engine warmed up: those not in
// `before`) run kernels at a lower priority than the threads that take calls, stream replies and
// do requests' host work: under heavy kernels a small request's host work and its client on the
// same machine would otherwise get a third of a core (a bystander's 1024x768 render waited
// 0.5-0.9 s beside six heavy requests, 0.45-0.6 s with this). The kernels lose nothing while the
// host is idle. Returns them.
std::set<pid_t> lower_device_threads(const std::set<pid_t>& before);

}  // namespace shadow
