# Finds the Boykov–Kolmogorov max-flow library (Debian package libmaxflow-dev).
# Defines the imported target Maxflow::Maxflow.
find_path(Maxflow_INCLUDE_DIR NAMES maxflow.h PATH_SUFFIXES maxflow-3.0)
find_library(Maxflow_LIBRARY NAMES maxflow)
include(FindPackageHandleStandardArgs)
find_package_handle_standard_args(Maxflow REQUIRED_VARS Maxflow_LIBRARY Maxflow_INCLUDE_DIR)
if(Maxflow_FOUND AND NOT TARGET Maxflow::Maxflow)
  add_library(Maxflow::Maxflow UNKNOWN IMPORTED)
  set_target_properties(Maxflow::Maxflow PROPERTIES
    IMPORTED_LOCATION "${Maxflow_LIBRARY}"
    INTERFACE_INCLUDE_DIRECTORIES "${Maxflow_INCLUDE_DIR}")
endif()
mark_as_advanced(Maxflow_INCLUDE_DIR Maxflow_LIBRARY)
