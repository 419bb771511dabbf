#!/usr/bin/env bash
# Time Bogoslavskyi & Stachniss' own C++ (PRBonn/depth_clustering) on a Moosmann-style log, for the
# same-session comparison of results/benchmark/cpp-comparison/. Their code is built here, outside
# the project, from a checkout that you give; nothing of it goes into flic. driver.cpp (ours) runs
# their Moosmann example's pipeline (show_objects_moosmann.cpp) without the viewer.
#
#   bash scripts/depth_clustering/time_cpp.sh DC_CHECKOUT LOG REPEAT > cpp.csv
#   bash scripts/depth_clustering/time_cpp.sh DC_CHECKOUT LOG dump OUT
#
# The second form writes their ground mask of every frame as OUT/NNNNN.ground (driver mode dump),
# for scripts/bogoslavskyi_fidelity.py.
#
# Needs g++, OpenCV 4 (pkg-config opencv4), Boost (filesystem, regex) and Eigen 3 headers, e.g.
# apt-get install g++ libopencv-dev libboost-filesystem-dev libboost-regex-dev libeigen3-dev,
# and the en_US.UTF-8 locale, which their folder reader sets (without it their code aborts:
# "locale::facet::_S_create_c_locale name not valid"; apt-get install locales, then enable it
# in /etc/locale.gen and run locale-gen).
# Prints frame,ground_and_clustering_us,clustering_us (median of REPEAT calls per frame).
set -euo pipefail
dc=$(realpath "$1") log=$(realpath "$2") repeat=${3:-3}
if [ "$repeat" = dump ]; then mkdir -p "$4"; out=$(realpath "$4"); fi
here=$(dirname "$(realpath "$0")")
build=$(mktemp -d)
trap 'rm -rf "$build"' EXIT
# their sources include <opencv/cv.h> (OpenCV 2/3) and a CMake-generated config header
mkdir -p "$build/inc/opencv"
for h in cv.h highgui.h; do
  printf '#pragma once\n#include <opencv2/opencv.hpp>\n#include <opencv2/imgcodecs/legacy/constants_c.h>\n' \
    > "$build/inc/opencv/$h"
done
printf '#pragma once\n#define USE_PCL 0\n#include <string>\nconst std::string SOURCE_PATH = "%s";\n' \
  "$dc" > "$build/inc/cmake_config.h"
src=$dc/src
# without libboost-regex-dev only the versioned runtime library is there: link it by path
regex=-lboost_regex
compgen -G "/usr/lib/*/libboost_regex.so" > /dev/null || regex=$(ls /usr/lib/*/libboost_regex.so.* | head -1)
g++ -O3 -DNDEBUG -std=c++17 -I"$build/inc" -I"$src" -I/usr/include/eigen3 \
  $(pkg-config --cflags opencv4) \
  "$here/driver.cpp" \
  "$src/ground_removal/depth_ground_remover.cpp" \
  "$src/projections/projection_params.cpp" "$src/projections/ring_projection.cpp" \
  "$src/projections/spherical_projection.cpp" "$src/projections/cloud_projection.cpp" \
  "$src/image_labelers/diff_helpers/angle_diff.cpp" \
  "$src/image_labelers/diff_helpers/line_dist_diff.cpp" \
  "$src/image_labelers/abstract_image_labeler.cpp" \
  "$src/communication/identifiable.cpp" \
  "$src/utils/cloud.cpp" "$src/utils/rich_point.cpp" "$src/utils/bbox.cpp" \
  "$src/utils/folder_reader.cpp" "$src/utils/velodyne_utils.cpp" \
  -o "$build/driver" \
  $(pkg-config --libs opencv4) -lboost_filesystem -lboost_system "$regex"
# their img.cfg reader wants the values line without the trailing ';' and no comment line
mkdir "$build/log"
ln -s "$log"/*.png "$build/log/"
grep -v '^#' "$log/img.cfg" | sed 's/;[[:space:]]*$//' > "$build/log/img.cfg"
if [ "$repeat" = dump ]; then
  "$build/driver" dump "$build/log" "$out"
else
  "$build/driver" time "$build/log" "$repeat"
fi
