#pragma once
// cv::imdecode from libopencv_imgcodecs, loaded on the first image decoded (image_file.cpp).
// Linking imgcodecs maps ~110 more shared libraries into every process (GDAL, GDCM, poppler, x265,
// OpenEXR...): 29 MB of naneyed's 66 MB resident memory on 2026-12-04, for a source (images://) most
// installations never open. dlopen keeps them out until one does.
#include <opencv2/core.hpp>

namespace naneye::driver {

// The library's cv::imdecode. Throws ImageError (naming the library and the Debian package) when
// the library or the symbol cannot be loaded.
cv::Mat imdecode_lazy(const cv::Mat& bytes, int flags);

}  // namespace naneye::driver
