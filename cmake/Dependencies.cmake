# All dependencies are Debian bookworm packages (scripts/install-deps installs them).
find_package(Eigen3 3.4 REQUIRED NO_MODULE)
find_package(yaml-cpp REQUIRED)
find_package(nlohmann_json 3 REQUIRED)
find_package(CLI11 REQUIRED)
find_package(TBB REQUIRED)
if(LASERCELL_BUILD_TESTS)
  find_package(GTest REQUIRED)
endif()
if(LASERCELL_BUILD_BENCHMARKS)
  find_package(benchmark REQUIRED)
endif()
find_package(nanoflann REQUIRED)
find_package(flann REQUIRED)  # only for the kd-tree comparison benchmark (bench/kdtree_benchmark.cpp)
find_package(Ceres 2 REQUIRED)  # all calibration solvers (calib/)
find_path(MRCAL_INCLUDE_DIR mrcal/mrcal.h REQUIRED)  # lens models (calib/, datasets/)
find_library(MRCAL_LIBRARY mrcal REQUIRED)
# OpenCV: image IO, chessboard/ChArUco detection (calib/), peer comparisons (tools/ only).
find_package(OpenCV 4 REQUIRED COMPONENTS core imgproc calib3d imgcodecs aruco)
set(LASERCELL_OPENCV_CALIB_LIBS opencv_core opencv_imgproc opencv_calib3d opencv_imgcodecs opencv_aruco)
# OpenCASCADE 7.6: STEP/IGES part models (localize/cad_import, localize/cad_export) only; its
# headers stay out of localize's public headers.
find_package(OpenCASCADE REQUIRED)
# Aravis 0.8: GigE Vision line-scan streams (triangulation/gige_source); its GLib headers stay out of
# triangulation's public headers.
find_package(PkgConfig REQUIRED)
pkg_check_modules(ARAVIS REQUIRED IMPORTED_TARGET aravis-0.8)
set(LASERCELL_OCCT_LIBS
  TKSTEP TKIGES TKXSBase      # STEP and IGES readers/writers, data-exchange settings
  TKMesh                      # tessellation (BRepMesh)
  TKPrim TKBO                 # primitives and Boolean operations (cad_export)
  TKShHealing                 # loose IGES faces -> oriented solids (ShapeFix_Solid)
  TKTopAlgo TKBRep TKGeomBase TKG3d TKG2d TKMath TKernel)
