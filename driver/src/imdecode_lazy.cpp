#include "imdecode_lazy.hpp"

#include <dlfcn.h>

#include <string>

#include "naneye/driver/image_file.hpp"

namespace naneye::driver {
namespace {

// cv::imdecode(cv::_InputArray const&, int), as the library exports it (Itanium C++ ABI mangling;
// the signature is part of the soname's ABI, so the soname pins it).
constexpr const char* kImdecodeSymbol = "_ZN2cv8imdecodeERKNS_11_InputArrayEi";
using ImdecodeFn = cv::Mat (*)(const cv::_InputArray&, int);

struct CodecsLibrary {
  ImdecodeFn fn = nullptr;
  std::string error;
};

CodecsLibrary load_codecs() {
  CodecsLibrary l;
  // RTLD_LOCAL: its symbols serve this call only; OpenCV's core, which it shares with us, is
  // already loaded and is used as is.
  void* h = dlopen(NANEYE_IMGCODECS_SONAME, RTLD_NOW | RTLD_LOCAL);
  if (!h) {
    const char* e = dlerror();
    l.error = std::string("cannot load " NANEYE_IMGCODECS_SONAME " (Debian package libopencv-imgcodecs") +
              NANEYE_IMGCODECS_SOVERSION + "): " + (e ? e : "unknown error");
    return l;
  }
  l.fn = reinterpret_cast<ImdecodeFn>(dlsym(h, kImdecodeSymbol));
  if (!l.fn) l.error = std::string(NANEYE_IMGCODECS_SONAME " has no cv::imdecode (") + kImdecodeSymbol + ")";
  return l;
}

}  // namespace

cv::Mat imdecode_lazy(const cv::Mat& bytes, int flags) {
  // Loaded once per process (a thread-safe static: the library stays mapped until exit, as a
  // linked one would).
  static const CodecsLibrary loaded = load_codecs();
  if (!loaded.fn) throw ImageError(loaded.error);
  return loaded.fn(bytes, flags);
}

}  // namespace naneye::driver
