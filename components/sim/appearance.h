#pragma once
// People's appearance: photos of real people cut from the shared data (INRIA Person samples
// and TUD-Campus frames, by their ground-truth boxes) so that a real HOG detector can
// recognise them in the rendered colour image. Without the data, a drawn figure.

#include <cstdint>
#include <string>
#include <vector>

namespace sarmap {
namespace sim {

// An RGB texture (8-bit, row 0 at the top) with the person's box inside it
// as fractions of the texture (the crop keeps a margin around the person as HOG expects).
struct Appearance {
  std::string origin;  // file and box it came from
  int width = 0, height = 0;
  std::vector<uint8_t> rgb;  // width*height*3
  double person_top = 0.125, person_bottom = 0.875;  // rows, fraction of height
};

// Crops up to `max_count` people from `data_dir`/vision/rgb. `warning` is set (and a drawn
// figure returned) when the data is missing or unreadable.
std::vector<Appearance> LoadAppearances(const std::string& data_dir, int max_count,
                                        std::string* warning);
// A simple drawn standing figure on a plain background.
Appearance DrawnFigure(int variant);

}  // namespace sim
}  // namespace sarmap
