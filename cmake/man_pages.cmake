# SPDX-License-Identifier: Apache-2.0
# Man pages generated from each program's --help at build time (scripts/help_to_man.py), installed to
# share/man with their program's install component. Not in sanitizer builds (nothing is packaged from them,
# and running each instrumented program would only cost time).
find_package(Python3 COMPONENTS Interpreter)
if(Python3_FOUND AND NOT RSU_SANITIZE AND NOT RSU_SANITIZE_THREAD)
  include(GNUInstallDirs)
  set(rsu_man_dir ${CMAKE_BINARY_DIR}/man)
  set(rsu_man_pages "")
  # rsu_man_page(TARGET SECTION COMPONENT SUMMARY [extra help_to_man.py arguments...])
  function(rsu_man_page target section component summary)
    if(NOT TARGET ${target})
      return()
    endif()
    set(page ${rsu_man_dir}/${target}.${section})
    add_custom_command(OUTPUT ${page}
                       COMMAND ${CMAKE_COMMAND} -E make_directory ${rsu_man_dir}
                       COMMAND ${Python3_EXECUTABLE} ${PROJECT_SOURCE_DIR}/scripts/help_to_man.py $<TARGET_FILE:${target}>
                               ${section} ${summary} ${page} --version ${PROJECT_VERSION} ${ARGN}
                       DEPENDS ${target} ${PROJECT_SOURCE_DIR}/scripts/help_to_man.py ${PROJECT_SOURCE_DIR}/deploy/rsud.8.files VERBATIM)
    install(FILES ${page} DESTINATION ${CMAKE_INSTALL_MANDIR}/man${section} COMPONENT ${component})
    set(rsu_man_pages ${rsu_man_pages} ${page} PARENT_SCOPE)
  endfunction()
  # rsud's FILES: where the Debian package puts them (cmake/packaging.cmake).
  rsu_man_page(rsud 8 daemon "roadside-unit LiDAR localization daemon" --files ${PROJECT_SOURCE_DIR}/deploy/rsud.8.files)
  rsu_man_page(rsu-vehicle 1 tools "vehicle side of RSU-assisted localization: announce, receive, fuse")
  rsu_man_page(rsu-autoware-sidecar 1 tools "RSU fixes as the vehicle's base_link pose for Autoware's ekf_localizer")
  rsu_man_page(rsu-sim 1 tools "LiDAR and scene simulator" --subcommand simulate --subcommand stream)
  rsu_man_page(rsu-keygen 1 tools "Ed25519 keys and trust lists for signed V2I messages")
  rsu_man_page(rsu-calibrate 1 tools "the LiDAR's mount from its background scan and the street's map")
  rsu_man_page(rsu-decode 1 tools "a LiDAR capture into one PCD file per rotation")
  rsu_man_page(rsu-relay 1 tools "V2I relay that impairs the link or tampers with corrections (tests)")
  rsu_man_page(rsu-vehicle-replay 1 tools "a recorded drive through the vehicle core again, offline")
  rsu_man_page(rsu-pilot 1 tools "the paper's pilot experiment")
  rsu_man_page(rsu-corridor 1 tools "the paper's realistic corridor experiment")
  add_custom_target(rsu_man_pages ALL DEPENDS ${rsu_man_pages})
endif()
