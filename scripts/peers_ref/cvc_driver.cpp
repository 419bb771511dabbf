// Runs xmba15/curved_voxel_clustering (built outside flic, /work/ref/) on float32 xyz files and
// writes one int32 label per point (-1: the reference's unclustered points) and the time.
// Build: see scripts/peers_fidelity.sh. Usage: cvc_driver IN.xyz OUT.labels [NUM_MIN_POINTS]
// (NUM_MIN_POINTS: the library's numMinPoints, default its own, 3; scripts/peers_study.py ablation)
#include <cstdlib>
#include <chrono>
#include <cstdio>
#include <fstream>
#include <vector>

#include <curved_voxel_clustering/CurvedVoxelClustering.hpp>

int main(int argc, char** argv)
{
    if (argc != 3 && argc != 4) {
        std::fprintf(stderr, "usage: %s IN.xyz OUT.labels [NUM_MIN_POINTS]\n", argv[0]);
        return 2;
    }
    std::ifstream in(argv[1], std::ios::binary | std::ios::ate);
    const std::size_t n = static_cast<std::size_t>(in.tellg()) / (3 * sizeof(float));
    in.seekg(0);
    std::vector<float> xyz(3 * n);
    in.read(reinterpret_cast<char*>(xyz.data()), 3 * n * sizeof(float));
    pcl::PointCloud<pcl::PointXYZ>::Ptr cloud(new pcl::PointCloud<pcl::PointXYZ>);
    cloud->resize(n);
    for (std::size_t i = 0; i < n; ++i) {
        (*cloud)[i].x = xyz[3 * i];
        (*cloud)[i].y = xyz[3 * i + 1];
        (*cloud)[i].z = xyz[3 * i + 2];
    }
    perception::CurvedVoxelClustering<pcl::PointXYZ>::Param param;  // the library's defaults
    if (argc == 4) param.numMinPoints = std::atoi(argv[3]);
    perception::CurvedVoxelClustering<pcl::PointXYZ> cvc(param);
    auto t0 = std::chrono::steady_clock::now();
    auto clusters = cvc.run(cloud);
    auto t1 = std::chrono::steady_clock::now();
    std::vector<int> labels(n, -1);
    for (std::size_t c = 0; c < clusters.size(); ++c)
        for (int i : clusters[c]) labels[i] = static_cast<int>(c);
    std::ofstream out(argv[2], std::ios::binary);
    out.write(reinterpret_cast<const char*>(labels.data()), n * sizeof(int));
    std::printf("%.6f\n", std::chrono::duration<double>(t1 - t0).count());
    return 0;
}
