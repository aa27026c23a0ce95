# kinegraph_add_plugin(): the one way a Kinegraph plugin is built, in this source tree
# (plugins/*/CMakeLists.txt) and outside it (after find_package(Kinegraph), which includes this
# file from <prefix>/lib/cmake/Kinegraph/).
#
#   kinegraph_add_plugin(<name> SOURCES <file>... [LIBS <target>...]
#                        [OUTPUT_DIRECTORY <dir>] [INSTALL_DESTINATION <dir>] [NO_INSTALL])
#
# builds <name>.so, a MODULE library (loaded with dlopen, never linked; no "lib" prefix, so that a
# graph's `plugins: [<name>]` and `kinegraph --plugin-dir` find it by that name), C++20, with
# hidden visibility (only the KG_PLUGIN entry points are exported), linking kg::graph and LIBS:
# what the plugin uses of Kinegraph's libraries, e.g. kg::motion_nodes for a node over kg.Motion
# ports, kg::retarget for a constraint kind. Host and plugin must come from the same compiler and
# Kinegraph headers (kg/graph/plugin_abi.hpp checks the ABI version when it loads).
#
# OUTPUT_DIRECTORY  where the build puts it: default ${KINEGRAPH_PLUGIN_OUTPUT_DIRECTORY} when
#                   set, else ${CMAKE_BINARY_DIR}/plugins. Run a graph with the plugins there
#                   with `kinegraph run graph.yaml --plugin-dir <that folder>`.
# INSTALL_DESTINATION  where `cmake --install` puts it: default ${KINEGRAPH_PLUGIN_INSTALL_DIR}
#                   when set, else lib/kinegraph/plugins. Installed into Kinegraph's own prefix,
#                   the CLI finds it by its bare name; elsewhere, name that folder in
#                   KINEGRAPH_PLUGIN_PATH or --plugin-dir. `INSTALL_DESTINATION
#                   ${Kinegraph_PLUGIN_DIR}` installs into Kinegraph's prefix whatever the
#                   project's CMAKE_INSTALL_PREFIX.
# NO_INSTALL        no install rule (test modules).
#
# Its install RPATH finds Kinegraph's libraries both when it is installed into Kinegraph's prefix
# ($ORIGIN/../.. for lib/kinegraph/plugins and lib/) and where they were linked from (a Kinegraph
# installed elsewhere).
include_guard(GLOBAL)

function(kinegraph_add_plugin name)
  cmake_parse_arguments(ARG "NO_INSTALL" "OUTPUT_DIRECTORY;INSTALL_DESTINATION" "SOURCES;LIBS" ${ARGN})
  if(ARG_UNPARSED_ARGUMENTS)
    message(FATAL_ERROR "kinegraph_add_plugin(${name}): unexpected arguments: ${ARG_UNPARSED_ARGUMENTS} "
                        "(usage: kinegraph_add_plugin(NAME SOURCES files... [LIBS targets...]))")
  endif()
  if(NOT ARG_SOURCES)
    message(FATAL_ERROR "kinegraph_add_plugin(${name}): no SOURCES")
  endif()
  if(NOT TARGET kg::graph)
    message(FATAL_ERROR "kinegraph_add_plugin(${name}): kg::graph is not defined; call "
                        "find_package(Kinegraph REQUIRED) first")
  endif()
  if(NOT ARG_OUTPUT_DIRECTORY)
    if(KINEGRAPH_PLUGIN_OUTPUT_DIRECTORY)
      set(ARG_OUTPUT_DIRECTORY ${KINEGRAPH_PLUGIN_OUTPUT_DIRECTORY})
    else()
      set(ARG_OUTPUT_DIRECTORY ${CMAKE_BINARY_DIR}/plugins)
    endif()
  endif()
  if(NOT ARG_INSTALL_DESTINATION)
    if(KINEGRAPH_PLUGIN_INSTALL_DIR)
      set(ARG_INSTALL_DESTINATION ${KINEGRAPH_PLUGIN_INSTALL_DIR})
    else()
      set(ARG_INSTALL_DESTINATION lib/kinegraph/plugins)
    endif()
  endif()

  add_library(${name} MODULE ${ARG_SOURCES})
  target_link_libraries(${name} PRIVATE kg::graph ${ARG_LIBS})
  target_compile_features(${name} PRIVATE cxx_std_20)
  set_target_properties(${name} PROPERTIES
    PREFIX ""
    SUFFIX ".so"
    CXX_EXTENSIONS OFF
    CXX_VISIBILITY_PRESET hidden
    LIBRARY_OUTPUT_DIRECTORY ${ARG_OUTPUT_DIRECTORY}
    INSTALL_RPATH_USE_LINK_PATH TRUE)  # Kinegraph's lib/ when linked from outside this project
  # Kinegraph's library folder relative to its prefix (lib, or lib/<multiarch> under /usr).
  set(libdir lib)
  if(KINEGRAPH_INSTALL_LIBDIR)
    set(libdir ${KINEGRAPH_INSTALL_LIBDIR})
  endif()
  if(NOT IS_ABSOLUTE "${ARG_INSTALL_DESTINATION}" AND NOT IS_ABSOLUTE "${libdir}")
    file(RELATIVE_PATH up /prefix/${ARG_INSTALL_DESTINATION} /prefix/${libdir})
    string(REGEX REPLACE "/$" "" up "${up}")
    set_target_properties(${name} PROPERTIES INSTALL_RPATH "$ORIGIN/${up}")
  endif()
  if(NOT ARG_NO_INSTALL)
    install(TARGETS ${name} LIBRARY DESTINATION ${ARG_INSTALL_DESTINATION})
  endif()
endfunction()
