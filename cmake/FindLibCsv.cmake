# Finds libcsv (Debian: libcsv-dev, runtime libcsv3), the RFC 4180 parser of the CSV inputs
# (src/data/csv_reader.cpp). It ships no CMake or pkg-config file, hence this module, which is
# installed beside combabcConfig.cmake so that a consumer of the static libraries finds it too.
# Defines LibCsv_FOUND and the imported target LibCsv::LibCsv.
find_path(LibCsv_INCLUDE_DIR NAMES csv.h)
find_library(LibCsv_LIBRARY NAMES csv)
include(FindPackageHandleStandardArgs)
find_package_handle_standard_args(LibCsv REQUIRED_VARS LibCsv_LIBRARY LibCsv_INCLUDE_DIR)
mark_as_advanced(LibCsv_INCLUDE_DIR LibCsv_LIBRARY)
if(LibCsv_FOUND AND NOT TARGET LibCsv::LibCsv)
  add_library(LibCsv::LibCsv UNKNOWN IMPORTED)
  set_target_properties(LibCsv::LibCsv PROPERTIES
    IMPORTED_LOCATION "${LibCsv_LIBRARY}"
    INTERFACE_INCLUDE_DIRECTORIES "${LibCsv_INCLUDE_DIR}")
endif()
