#!/usr/bin/env bash
# How the references of scripts/peers_study.py were obtained and built, outside flic, under
# /work/ref/ (nothing of theirs is copied into flic). Debian 12, 2 shared cores.
#   valeoai/Alpine                      (pure Python, MIT): used from its clone
#   xmba15/curved_voxel_clustering      (C++, PCL): its library + scripts/peers_ref/cvc_driver.cpp
#   placeforyiming/ICCVW21-LiDAR-Panoptic-Segmentation-TradiCV-Survey-of-Point-Cloud-Cluster
#                                       (C++/pybind11, PCL): PC_cluster/ScanLineRun_cluster
# The clones came from the session's GitHub mirror (`fetch` tool), checked out as:
#   git clone <mirror>/valeoai+Alpine/repo /work/ref/valeoai+Alpine   (etc.)
set -euo pipefail
ref=${FLIC_REF:-/work/ref}
here=$(cd "$(dirname "$0")" && pwd)
apt-get install -y -q --no-install-recommends libpcl-dev pybind11-dev libeigen3-dev
pyinc=$(python3 -c "import sysconfig; print(sysconfig.get_paths()['include'])")
ext=$(python3 -c "import sysconfig; print(sysconfig.get_config_var('EXT_SUFFIX'))")
# The survey's CMakeLists wants OpenCV and a cloned pybind11; the module itself includes only
# PCL, Eigen and pybind11, so it is compiled directly:
mkdir -p "$ref/build_slr"
g++ -O3 -std=c++14 -shared -fPIC -I/usr/include/pcl-1.13 -I/usr/include/eigen3 -I"$pyinc" \
  "$ref"/placeforyiming+ICCVW21-LiDAR-Panoptic-Segmentation-TradiCV-Survey-of-Point-Cloud-Cluster/PC_cluster/ScanLineRun_cluster/ScanLineRun_Cluster.cpp \
  -o "$ref/build_slr/ScanLineRun_Cluster$ext" -lpcl_common -lpcl_io
mkdir -p "$ref/build_cvc"
g++ -O3 -std=c++17 -I"$ref/xmba15+curved_voxel_clustering/include" -I/usr/include/pcl-1.13 \
  -I/usr/include/eigen3 "$ref/xmba15+curved_voxel_clustering/src/CurvedVoxelClustering.cpp" \
  "$here/peers_ref/cvc_driver.cpp" -o "$ref/build_cvc/cvc_driver" -lpcl_common
mkdir -p "$ref/build_euclidean"
g++ -O3 -std=c++17 -I/usr/include/pcl-1.13 -I/usr/include/eigen3 "$here/peers_ref/euclidean_driver.cpp" \
  -o "$ref/build_euclidean/euclidean_driver" -lpcl_common -lpcl_search -lpcl_kdtree -lpcl_segmentation
# then, from the project root:
#   python scripts/peers_study.py clusterers ../shared/data/semantickitti results/peers/fidelity
#   python scripts/peers_study.py ref-diff ../shared/data/semantickitti > results/peers/fidelity/ref_diff.txt
