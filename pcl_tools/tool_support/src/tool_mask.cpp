#include "occ_improve/tools/tool_mask.hpp"

#include "occ_improve/errors.hpp"
#include "occ_improve/io/png.hpp"
#include "occ_improve/pcl/conversion.hpp"

#include <exception>
#include <utility>

namespace occ_improve {

namespace {

// A mask of no valid pixel leaves nothing to map, plan or segment: occ_segment wrote an empty segmentation
// and -simulate stopped at once, both exiting 0.
PixelMask with_some_pixel(PixelMask mask, const std::string& value) {
  if (mask.valid_count() == 0) throw InvalidParameter("-mask " + value + " leaves out every pixel");
  return mask;
}

}  // namespace

std::optional<PixelMask> read_tool_mask(const CommandLine& command_line, const ToolFrame* first) {
  if (!command_line.declares("-mask") || !command_line.has("-mask")) return std::nullopt;
  const std::string value = *command_line.text("-mask");
  if (value != "finite") {
    PixelMask mask;
    try {
      mask = read_mask_png(value);
    } catch (const std::exception& e) {
      throw InvalidParameter("-mask " + value + ": " + e.what());
    }
    return with_some_pixel(std::move(mask), value);
  }
  if (!first) throw InvalidParameter("-mask finite needs an input frame (it is the first frame's valid pixels)");
  const auto& cloud = first->cloud;
  if (cloud.height <= 1)
    throw InvalidParameter("-mask finite: '" + first->name + "' is not organized, so its points name no pixel");
  return with_some_pixel(finite_pixel_mask(span_of(cloud), static_cast<int>(cloud.width), static_cast<int>(cloud.height)),
                         value);
}

namespace {
// Runs `use` on the mask, naming -mask and its source in a refusal (the core's message names sizes only).
template <typename Use>
auto with_mask_named(const CommandLine& command_line, Use use) {
  try {
    return use();
  } catch (const InvalidInput& e) {
    throw InvalidParameter("-mask " + *command_line.text("-mask") + ": " + e.what());
  } catch (const InvalidParameter& e) {
    const std::string what = e.what();
    if (what.rfind("-mask", 0) == 0) throw;
    throw InvalidParameter("-mask " + *command_line.text("-mask") + ": " + what);
  }
}
}  // namespace

std::string apply_tool_mask(const CommandLine& command_line, Mapper& mapper, const ToolFrame* first) {
  return with_mask_named(command_line, [&] {
    const std::optional<PixelMask> mask = read_tool_mask(command_line, first);
    if (!mask) return std::string();
    mapper.set_mask(*mask);
    return "mask " + *command_line.text("-mask") + ": " + std::to_string(mask->valid_count()) + " of " +
           std::to_string(mask->valid.size()) + " pixels valid";
  });
}

std::vector<std::uint8_t> tool_mask_columns(const CommandLine& command_line, const GridGeometry& geometry,
                                            const PixelMask& mask) {
  return with_mask_named(command_line, [&] { return mask_columns(geometry, mask); });
}

}  // namespace occ_improve
