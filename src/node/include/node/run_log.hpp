#pragma once
// What `motormix run` writes to its log besides warnings: the start-up
// banner (describe_run, the lcm url, the matrix), a change of the failure
// set, and the spin landing's steps. Lines only; the node decides when.

#include "loop/control_loop.hpp"

#include <motormix/config/config.hpp>

#include <iosfwd>
#include <string>

namespace motormix::node {

void log_summary(const config::Config& config, const loop::ControlLoop& loop,
                 const std::string& url, std::ostream& log);
void log_failures(std::ostream& log, const config::Config& config, const loop::CycleResult& r);
void log_landing(std::ostream& log, const config::Config& config, const loop::CycleResult& r);

}  // namespace motormix::node
