// occ_segment: segments an organized range frame along its negative-improvement contours (the paper's
// closing remark) and writes a labelled cloud, label and contour images and a per-segment table.
#include "occ_improve/cancel.hpp"
#include "occ_improve/errors.hpp"
#include "occ_improve/io/png.hpp"
#include "occ_improve/pcl/pcd_writer.hpp"
#include "occ_improve/pcl/cloud_segmentation.hpp"
#include "occ_improve/pcl/conversion.hpp"
#include "occ_improve/pcl/frame_io.hpp"
#include "occ_improve/tools/frame_fusion.hpp"
#include "occ_improve/tools/input_scope.hpp"
#include "occ_improve/tools/output_files.hpp"
#include "occ_improve/tools/segmentation_flags.hpp"
#include "occ_improve/tools/tool_frames.hpp"
#include "occ_improve/tools/tool_main.hpp"
#include "occ_improve/tools/tool_mask.hpp"
#include "occ_improve/tools/tool_options.hpp"

#include <pcl/common/transforms.h>
#include <pcl/io/pcd_io.h>

#include <cstdio>
#include <fstream>

namespace {

using namespace occ_improve;

const ToolFlags kFlags{
    "occ_segment",
    {"INPUT -o OUTDIR [options]", "-input_dir DIR -output_dir OUTDIR [options]   (each frame file of DIR, into OUTDIR/<stem>/)"},
    "Segments one organized frame along its negative-improvement contours (the paper's closing remark).\n"
    "Writes into OUTDIR: labels.pcd (PointXYZRGBL, opens in pcl_viewer), labels.png (the segments'\n"
    "colours), label_ids.png (16-bit label per ray, 0 = none: what pcl_pcd2png --field label writes),\n"
    "contours.png, segments.csv (label, rays, points, centroid x y z, mean depth, plane).\n",
    joined({output_folder_flag_names(), {"-q", "-contour", "-min_segment", "-no_plane", "-plane_distance"}, sensor_flag_names(),
            camera_flag_names(), {"-mask"}, batch_flag_names()}),
    {},
    {},
    frame_inputs_help(false)};

// The label of each ray as a 16-bit id (0 = no segment), as PCL's pcl_pcd2png writes a label field ("mono").
Image16 label_id_image(const Segmentation& segmentation) {
  if (segmentation.segments.size() > 65535)
    throw InvalidParameter("label_ids.png holds 16-bit labels: " + std::to_string(segmentation.segments.size()) +
                           " segments are too many (raise -min_segment)");
  Image16 image{segmentation.width, segmentation.height, std::vector<std::uint16_t>(segmentation.label.size())};
  std::copy(segmentation.label.begin(), segmentation.label.end(), image.pixels.begin());
  return image;
}

int run(const CommandLine& command_line) {
  const ToolOptions options = parse_tool_options(command_line);
  if (options.inputs.size() != 1) throw InvalidParameter("give exactly one input frame (see -h)");
  // Fail on an unwritable or foreign output folder before any work.
  OutputFolder out = open_output_folder(command_line);

  const std::vector<ToolFrame> frames = read_tool_frames(options);
  if (frames.size() != 1)
    throw InvalidParameter("give exactly one input frame (" + options.inputs.front() + " holds " +
                           std::to_string(frames.size()) + ")");
  const ToolFrame& frame = frames.front();
  const InputScope scope(frame.name);
  if (frame.cloud.height <= 1)
    throw InvalidInput("'" + frame.name + "' is not organized (height 1): the segmentation needs a range image");
  throw_if_stop_requested();
  const SensorPreset preset = options.preset_for_camera(frame.camera);
  std::printf("%s\n", describe_camera(frames).c_str());
  SegmentationParams params = segmentation_defaults(preset);
  apply_segmentation_flags(command_line, params);

  const std::optional<PixelMask> mask = read_tool_mask(command_line, &frame);
  if (mask) tool_mask_columns(command_line, GridGeometry(preset.geometry), *mask);  // refused naming -mask
  const CloudSegmentation result = segment_cloud(frame.cloud, preset, params, options.grid, mask ? &*mask : nullptr);
  throw_if_stop_requested();
  // Segments need returns inside the grid: a frame whose points all lie beyond (or before) the depth range
  // gave empty outputs and exit 0, its points counted nowhere.
  if (!has_points_in_depth_range(result.mapping.insertion))
    throw InvalidInput(nothing_in_depth_range("'" + frame.name + "'", preset.geometry, result.mapping.insertion,
                                              "nothing to segment"));

  pcl::PointCloud<pcl::PointXYZRGBL> labelled;
  labelled.width = frame.cloud.width;
  labelled.height = frame.cloud.height;
  labelled.is_dense = false;
  labelled.resize(frame.cloud.size());
  std::vector<std::size_t> points_per_label(result.segmentation.segments.size() + 1, 0);
  for (std::size_t i = 0; i < frame.cloud.size(); ++i) {
    auto& q = labelled[i];
    q.x = frame.cloud[i].x;
    q.y = frame.cloud[i].y;
    q.z = frame.cloud[i].z;
    q.label = result.point_labels[i];
    ++points_per_label[std::min(q.label, static_cast<std::uint32_t>(points_per_label.size() - 1))];
    // The label image's colour for this label, so the cloud and labels.png agree.
    const auto rgb = segment_colour(q.label);
    q.r = rgb[0];
    q.g = rgb[1];
    q.b = rgb[2];
  }
  // Back in the frame the input file holds its points in, with its VIEWPOINT: labels.pcd overlays the input
  // (a cloud with a real VIEWPOINT came out in the sensor frame, up to metres away from it).
  const Eigen::Isometry3d to_file = frame.file_from_sensor.value_or(Eigen::Isometry3d::Identity());
  if (frame.file_from_sensor) {
    pcl::transformPointCloud(labelled, labelled, to_file.matrix().cast<float>());
    labelled.sensor_origin_ << to_file.translation().cast<float>(), 0.0f;
    labelled.sensor_orientation_ = Eigen::Quaternionf(to_file.linear().cast<float>());
  }
  save_pcd_binary(out.file("labels.pcd"), labelled);
  write_png(out.file("labels.png"), render_segmentation(result.segmentation));
  write_png(out.file("label_ids.png"), label_id_image(result.segmentation));
  write_png(out.file("contours.png"), render_contours(result.segmentation));
  const std::string csv_path = out.file("segments.csv");
  std::ofstream csv(csv_path);
  if (!csv) throw IoError("cannot write '" + csv_path + "'");
  csv << "label,rays,points,centroid_x_m,centroid_y_m,centroid_z_m,mean_depth_m,plane\n";
  for (const Segment& s : result.segmentation.segments) {
    const Eigen::Vector3d centroid = to_file * s.centroid_m;  // in labels.pcd's frame
    csv << s.label << ',' << s.columns << ',' << points_per_label[s.label] << ',' << centroid.x() << ',' << centroid.y()
        << ',' << centroid.z() << ',' << s.mean_depth_m << ',' << (s.plane ? 1 : 0) << '\n';
  }
  csv.close();
  if (!csv) throw IoError("cannot write '" + csv_path + "'");
  throw_if_stop_requested();  // before anything is committed: an interrupted run leaves nothing behind
  out.commit();

  const Segmentation& seg = result.segmentation;
  std::printf("preset %s, contour < %.3f, min segment %zu rays, dominant plane %s\n", preset.name.c_str(),
              params.contour_improvement_below, params.min_segment_columns,
              params.remove_dominant_plane ? "removed" : "kept");
  std::printf("%s\n", describe_points(result.mapping.insertion).c_str());
  std::printf("rays: %zu valid, %zu contour, %zu attached, %zu plane; %zu segments; %zu valid points outside the grid\n",
              seg.valid_columns, seg.contour_columns, seg.attached_columns, seg.plane_columns, seg.segments.size(),
              result.points_outside_grid);
  std::printf("time [ms]: map %.1f, segmentation %.1f, labelling %.1f, total %.1f\n", 1e3 * result.mapping_seconds,
              1e3 * result.segmentation_seconds, 1e3 * result.labelling_seconds, 1e3 * result.total_seconds());
  if (mask)
    std::printf("mask %s: %zu of %zu pixels valid; %zu valid points outside it left out\n",
                command_line.text("-mask")->c_str(), mask->valid_count(), mask->valid.size(),
                result.mapping.points_masked);
  std::printf("wrote %s/: labels.pcd labels.png label_ids.png contours.png segments.csv\n", out.path().c_str());
  return 0;
}

}  // namespace

int main(int argc, char** argv) { return occ_improve::run_tool(argc, argv, kFlags, run); }
