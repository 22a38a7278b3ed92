# nbv_add_module(<name> <sources>...): one folder, one target. Makes the library nbv_<name>
# with the alias nbv::<name>, requiring C++20 of itself and its users, public headers in the folder's include/, the project's warnings,
# and installs and exports it for find_package(nbv).
function(nbv_add_module name)
  add_library(nbv_${name} ${ARGN})
  add_library(nbv::${name} ALIAS nbv_${name})
  set_target_properties(nbv_${name} PROPERTIES EXPORT_NAME ${name} OUTPUT_NAME nbv_${name})
  # The public headers use C++20 (std::span, designated initialisers): a consumer gets it too.
  target_compile_features(nbv_${name} PUBLIC cxx_std_20)
  target_include_directories(nbv_${name} PUBLIC
    $<BUILD_INTERFACE:${CMAKE_CURRENT_SOURCE_DIR}/include>
    $<INSTALL_INTERFACE:${CMAKE_INSTALL_INCLUDEDIR}>)
  nbv_target_warnings(nbv_${name})
  # Every module's library, for what installs them all (the wheel: python/CMakeLists.txt).
  set_property(GLOBAL APPEND PROPERTY NBV_MODULE_TARGETS nbv_${name})
  install(TARGETS nbv_${name} EXPORT nbvTargets
          ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR}
          LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR})
  install(DIRECTORY include/ DESTINATION ${CMAKE_INSTALL_INCLUDEDIR})
endfunction()
