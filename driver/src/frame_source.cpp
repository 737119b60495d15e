#include "naneye/driver/frame_source.hpp"
#include "naneye/base/enum_table.hpp"

namespace naneye::driver {

namespace {
constexpr base::EnumTable<SourceState, 7> kSourceStateNames{
    {{SourceState::starting, "starting"},
     {SourceState::streaming, "streaming"},
     {SourceState::waiting_for_device, "waiting_for_device"},
     {SourceState::stalled, "stalled"},
     {SourceState::finished, "finished"},
     {SourceState::failed, "failed"},
     {SourceState::stopped, "stopped"}}};
}  // namespace

const char* to_string(SourceState s) {
  return base::enum_name(kSourceStateNames, s);
}

bool has_ended(SourceState s) {
  return s == SourceState::finished || s == SourceState::failed || s == SourceState::stopped;
}

}  // namespace naneye::driver
