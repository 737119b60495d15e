#pragma once
// Every source scheme the CLI opens: the driver's (usb, v4l2, file) and the simulator's sim://.
#include "naneye/driver/source_registry.hpp"
#include "naneye/sim/sim_source.hpp"

namespace naneye::tools {

inline driver::SourceRegistry make_registry() {
  driver::SourceRegistry registry = driver::make_default_registry();
  sim::register_sim_source(registry);
  return registry;
}

}  // namespace naneye::tools
