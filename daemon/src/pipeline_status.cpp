#include "naneye/daemon/pipeline_status.hpp"

#include "naneye/base/enum_table.hpp"

namespace naneye::daemon {
namespace {

constexpr base::EnumTable<ServiceState, 5> kServiceStateNames{
    {{ServiceState::starting, "starting"},
     {ServiceState::streaming, "streaming"},
     {ServiceState::waiting_for_device, "waiting_for_device"},
     {ServiceState::stalled, "stalled"},
     {ServiceState::stopped, "stopped"}}};

}  // namespace

const char* to_string(ServiceState s) {
  return base::enum_name(kServiceStateNames, s);
}

ServiceState service_state(bool stopping, std::optional<driver::SourceState> src, bool waiting,
                           std::optional<double> last_result_age_ms, int stall_timeout_ms) {
  using driver::SourceState;
  if (stopping) return ServiceState::stopped;
  if (!src || waiting || *src == SourceState::waiting_for_device || *src == SourceState::failed)
    return ServiceState::waiting_for_device;
  if (*src == SourceState::finished || *src == SourceState::stopped) return ServiceState::stopped;
  if (*src == SourceState::stalled) return ServiceState::stalled;
  if (!last_result_age_ms) return ServiceState::starting;
  if (*last_result_age_ms > stall_timeout_ms) return ServiceState::stalled;
  return ServiceState::streaming;
}

}  // namespace naneye::daemon
