// Runs PCL's EuclideanClusterExtraction (the reference of flic's `euclidean`) on a float32 xyz
// file; writes one int32 label per point (-1: in no cluster) and prints the time of extract().
// Build: see scripts/peers_fidelity.sh. Usage: euclidean_driver IN.xyz OUT.labels TOLERANCE_M
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <vector>

#include <pcl/point_types.h>
#include <pcl/search/kdtree.h>
#include <pcl/segmentation/extract_clusters.h>

int main(int argc, char** argv)
{
    if (argc != 4) {
        std::fprintf(stderr, "usage: %s IN.xyz OUT.labels TOLERANCE_M\n", argv[0]);
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
    auto t0 = std::chrono::steady_clock::now();
    pcl::search::KdTree<pcl::PointXYZ>::Ptr tree(new pcl::search::KdTree<pcl::PointXYZ>);
    tree->setInputCloud(cloud);
    std::vector<pcl::PointIndices> clusters;
    pcl::EuclideanClusterExtraction<pcl::PointXYZ> ec;
    ec.setClusterTolerance(std::atof(argv[3]));
    ec.setMinClusterSize(1);
    ec.setMaxClusterSize(static_cast<int>(n) + 1);
    ec.setSearchMethod(tree);
    ec.setInputCloud(cloud);
    ec.extract(clusters);
    auto t1 = std::chrono::steady_clock::now();
    std::vector<int> labels(n, -1);
    for (std::size_t c = 0; c < clusters.size(); ++c)
        for (int i : clusters[c].indices) labels[i] = static_cast<int>(c);
    std::ofstream out(argv[2], std::ios::binary);
    out.write(reinterpret_cast<const char*>(labels.data()), n * sizeof(int));
    std::printf("%.6f\n", std::chrono::duration<double>(t1 - t0).count());
    return 0;
}
