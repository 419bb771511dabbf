// Measurement driver (ours; not part of the flic package): runs PRBonn/depth_clustering's
// DepthGroundRemover and ImageBasedClusterer on a Moosmann-style log. Their code is built outside
// the project from a checkout (time_cpp.sh shows how). Modes:
//   driver dump LOG OUT [fix]   : write per frame OUT/NNNNN.ground (uint8 H*W) and .repaired (float32)
//   driver time LOG REPEAT [fix]: per-frame microseconds of ground+clustering and clustering alone
#include <cstdio>
#include <fstream>
#include <string>
#include <vector>
#include <algorithm>
#include <chrono>
#include "clusterers/image_based_clusterer.h"
#include "ground_removal/depth_ground_remover.h"
#include "image_labelers/diff_helpers/diff_factory.h"
#include "image_labelers/linear_image_labeler.h"
#include "projections/projection_params.h"
#include "utils/cloud.h"
#include "utils/folder_reader.h"
#include "utils/radians.h"
#include "utils/velodyne_utils.h"
using namespace depth_clustering;

struct Exposed : public DepthGroundRemover {
  using DepthGroundRemover::DepthGroundRemover;
  cv::Mat repaired, angle, smooth;
  cv::Mat NoGround(const cv::Mat& depth) {
    repaired = RepairDepth(depth, 5, 1.0f);
    angle = CreateAngleImage(repaired);
    smooth = ApplySavitskyGolaySmoothing(angle, _window_size);
    return ZeroOutGroundBFS(repaired, smooth, _ground_remove_angle, _window_size);
  }
};

static cv::Mat ReadRaw(const std::string& path) {
  cv::Mat d = cv::imread(path, cv::IMREAD_ANYDEPTH);
  d.convertTo(d, CV_32F);
  d /= 500.;
  return d;
}

int main(int argc, char** argv) {
  std::string mode = argv[1], log = argv[2];
  bool fix = argc > 4 && std::string(argv[4]) == "fix";
  auto paths = FolderReader(log, ".png", FolderReader::Order::SORTED).GetAllFilePaths();
  auto params = ProjectionParams::FromConfigFile(log + "/img.cfg");
  Exposed remover(*params, 9_deg, 5);
  if (mode == "dump") {
    std::string out = argv[3];
    for (size_t i = 0; i < paths.size(); ++i) {
      cv::Mat depth = fix ? MatFromDepthPng(paths[i]) : ReadRaw(paths[i]);
      cv::Mat ng = remover.NoGround(depth);
      cv::Mat ground(depth.size(), CV_8U);
      for (int r = 0; r < depth.rows; ++r)
        for (int c = 0; c < depth.cols; ++c)
          ground.at<uint8_t>(r, c) = remover.repaired.at<float>(r, c) > 0.001f && ng.at<float>(r, c) == 0.f;
      char name[512];
      snprintf(name, sizeof name, "%s/%05zu", out.c_str(), i);
      std::ofstream(std::string(name) + ".ground", std::ios::binary).write((char*)ground.data, ground.total());
      std::ofstream(std::string(name) + ".repaired", std::ios::binary).write((char*)remover.repaired.data, remover.repaired.total() * 4);
      std::ofstream(std::string(name) + ".smooth", std::ios::binary).write((char*)remover.smooth.data, remover.smooth.total() * 4);
      std::ofstream(std::string(name) + ".angle", std::ios::binary).write((char*)remover.angle.data, remover.angle.total() * 4);
    }
    printf("%zu frames, %d x %d\n", paths.size(), 0, 0);
    return 0;
  }
  // time: the example's Moosmann pipeline (show_objects_moosmann.cpp) without the viewer
  int repeat = std::stoi(argv[3]);
  ImageBasedClusterer<LinearImageLabeler<>> clusterer(10_deg, 20, 100000);
  clusterer.SetDiffType(DiffFactory::DiffType::ANGLES);
  DepthGroundRemover ground_remover(*params, 9_deg, 5);
  ground_remover.AddClient(&clusterer);
  printf("frame,ground_and_clustering_us,clustering_us\n");
  for (size_t i = 0; i < paths.size(); ++i) {
    cv::Mat depth = fix ? MatFromDepthPng(paths[i]) : ReadRaw(paths[i]);
    auto cloud = Cloud::FromImage(depth, *params);
    std::vector<double> both, alone;
    for (int k = 0; k < repeat; ++k) {
      auto t0 = std::chrono::steady_clock::now();
      ground_remover.OnNewObjectReceived(*cloud, 0);
      auto t1 = std::chrono::steady_clock::now();
      clusterer.OnNewObjectReceived(*cloud, 0);
      auto t2 = std::chrono::steady_clock::now();
      both.push_back(std::chrono::duration<double, std::micro>(t1 - t0).count());
      alone.push_back(std::chrono::duration<double, std::micro>(t2 - t1).count());
    }
    std::sort(both.begin(), both.end()); std::sort(alone.begin(), alone.end());
    printf("%zu,%.1f,%.1f\n", i, both[both.size() / 2], alone[alone.size() / 2]);
  }
  return 0;
}
