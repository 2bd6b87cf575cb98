# Host reference solvers for basis encodings (encode/solvers.h). Kept in its
# own library so it builds before and independently of the basis code;
# server/engine/encode/CMakeLists.txt includes this file when present, and
# tests/unit/encode includes it itself if that has not happened.
if(NOT TARGET luxel_encode_solvers)
  add_library(luxel_encode_solvers STATIC ${CMAKE_CURRENT_LIST_DIR}/solvers.cpp)
  target_link_libraries(luxel_encode_solvers PUBLIC luxel_common)
endif()
