#pragma once
// Reads an organized PCD file (x y z [rgb|rgba]) into an RgbdFrame. The only translation unit
// of this component that includes PCL's I/O headers.

#include <string>

#include "vision_people/people_detector.h"

namespace sarmap {
namespace vision_people {

// False with `error` set when the file cannot be read or is not organized. Colour is filled
// when the file has an rgb or rgba field. `intrinsics` are those of the registered image.
bool LoadPcdFrame(const std::string& path, const PinholeIntrinsics& intrinsics, RgbdFrame* frame,
                  std::string* error);

}  // namespace vision_people
}  // namespace sarmap
