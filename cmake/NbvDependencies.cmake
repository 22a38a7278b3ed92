# Every system package the nbv libraries need, found once. Also used by nbvConfig.cmake,
# so a consumer of the installed package finds the same dependencies.
include(CMakeFindDependencyMacro)

find_dependency(Eigen3 3.3 NO_MODULE)
find_dependency(TBB)
find_dependency(octomap)
find_dependency(embree 3)
find_dependency(assimp)
find_dependency(nanoflann)
find_dependency(nlohmann_json 3)
# Debian ships OpenVDB's FindOpenVDB.cmake beside its other CMake modules: the one place
# this project names that path.
list(APPEND CMAKE_MODULE_PATH /usr/lib/x86_64-linux-gnu/cmake/OpenVDB /usr/lib/cmake/OpenVDB)
# That module prints "COMPONENT = openvdb" as a notice on every configure, also in every
# project that finds nbv: it is looked for with notices hidden (the caller's log level
# restored), and only a failure goes through find_dependency, which says why and returns.
if(DEFINED CMAKE_MESSAGE_LOG_LEVEL)
  set(_nbv_message_log_level "${CMAKE_MESSAGE_LOG_LEVEL}")
endif()
set(CMAKE_MESSAGE_LOG_LEVEL WARNING)
find_package(OpenVDB QUIET)
if(DEFINED _nbv_message_log_level)
  set(CMAKE_MESSAGE_LOG_LEVEL "${_nbv_message_log_level}")
  unset(_nbv_message_log_level)
else()
  unset(CMAKE_MESSAGE_LOG_LEVEL)
endif()
if(NOT OpenVDB_FOUND)
  find_dependency(OpenVDB)
endif()

# OctoMap's config gives variables, not a target; wrap them once.
if(NOT TARGET nbv_octomap)
  add_library(nbv_octomap INTERFACE IMPORTED)
  target_include_directories(nbv_octomap INTERFACE ${OCTOMAP_INCLUDE_DIRS})
  target_link_libraries(nbv_octomap INTERFACE ${OCTOMAP_LIBRARIES})
  # Without NDEBUG (Debug and sanitizer builds) OctoMap's header templates print progress
  # ("Writing N nodes to output stream...") on stderr; nbv's library says nothing there.
  target_compile_definitions(nbv_octomap INTERFACE OCTOMAP_NODEBUGOUT)
endif()
