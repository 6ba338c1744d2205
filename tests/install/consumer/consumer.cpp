// Uses lasercell through its installed package: reads a cloud (core), estimates its normals
// (registration), loads a cell (core's frame graph) and asks the CAD reader (localize, on
// OpenCASCADE) for a file that does not exist. Prints one line per step; exit 0 when all ran.
#include <cstdio>
#include <exception>

#include "core/error.hpp"
#include "core/frame_graph.hpp"
#include "core/io/point_cloud_io.hpp"
#include "localize/cad_import.hpp"
#include "registration/normals.hpp"

int main(int argc, char** argv) {
  if (argc != 3) {
    std::fprintf(stderr, "usage: consumer CLOUD.ply CELL.yaml\n");
    return 2;
  }
  try {
    const lasercell::PointCloud cloud = lasercell::io::ReadPointCloud(argv[1]);
    const auto normals = lasercell::registration::EstimateNormals(cloud, {});
    std::printf("points %zu normals %zu\n", cloud.size(), cloud.size() - normals.invalid_count);
    const lasercell::FrameGraph cell = lasercell::LoadFrameGraph(argv[2]);
    std::printf("frames %zu\n", cell.Frames().size());
    try {
      lasercell::localize::ReadCadModel("no_such_part.step");
      std::printf("cad read a missing file\n");
      return 1;
    } catch (const lasercell::InputError& e) {
      std::printf("cad refused a missing file\n");
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "consumer: %s\n", e.what());
    return 1;
  }
  return 0;
}
