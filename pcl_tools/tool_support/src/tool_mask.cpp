#include "occ_improve/tools/tool_mask.hpp"

#include "occ_improve/errors.hpp"
#include "occ_improve/io/png.hpp"
#include "occ_improve/pcl/conversion.hpp"

#include <exception>

namespace occ_improve {

std::optional<PixelMask> read_tool_mask(const CommandLine& command_line, const ToolFrame* first) {
  if (!command_line.declares("-mask") || !command_line.has("-mask")) return std::nullopt;
  const std::string value = *command_line.text("-mask");
  if (value != "finite") {
    try {
      return read_mask_png(value);
    } catch (const std::exception& e) {
      throw InvalidParameter("-mask " + value + ": " + e.what());
    }
  }
  if (!first) throw InvalidParameter("-mask finite needs an input frame (it is the first frame's valid pixels)");
  const auto& cloud = first->cloud;
  if (cloud.height <= 1)
    throw InvalidParameter("-mask finite: '" + first->name + "' is not organized, so its points name no pixel");
  return finite_pixel_mask(span_of(cloud), static_cast<int>(cloud.width), static_cast<int>(cloud.height));
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
