# SPDX-License-Identifier: Apache-2.0
# Debian packages with CPack (`cpack -G DEB` in a build tree; README "Packages"): one package per install
# component.
#   rsud                         daemon: rsud, its systemd unit, /etc/rsud/ (conffiles), the sysctl snippet
#   rsu-tools                    tools: rsu-keygen, rsu-vehicle, rsu-sim and the other programs
#   librsu-vehicle-client0       library: the vehicle client's shared library (SOVERSION 0)
#   librsu-vehicle-client-dev    dev: its headers, CMake package, pkg-config file, the .so link
# Dependencies on Debian's libraries come from dpkg-shlibdeps; between our packages from the components'.
# CPACK_SET_DESTDIR installs with the prefix /usr under DESTDIR, so the unit names /usr/sbin/rsud and the
# configuration lands in /etc (deploy/install_unit_and_config.cmake).
set(CPACK_GENERATOR DEB)
set(CPACK_PACKAGE_NAME rsu-localize)
set(CPACK_PACKAGE_VENDOR "rsu-localize")
set(CPACK_PACKAGE_CONTACT "rsu-localize maintainers <rsu-localize@localhost>")
set(CPACK_PACKAGE_DESCRIPTION_SUMMARY "Roadside-unit LiDAR localization of connected vehicles")
set(CPACK_RESOURCE_FILE_LICENSE ${PROJECT_SOURCE_DIR}/LICENSE)
set(CPACK_PACKAGING_INSTALL_PREFIX /usr)
set(CPACK_INSTALL_PREFIX /usr)
set(CPACK_SET_DESTDIR ON)
set(CPACK_STRIP_FILES ON)
set(CPACK_DEB_COMPONENT_INSTALL ON)
set(CPACK_COMPONENTS_ALL daemon tools library dev)
set(CPACK_DEBIAN_FILE_NAME DEB-DEFAULT)
set(CPACK_DEBIAN_PACKAGE_SHLIBDEPS ON)
set(CPACK_DEBIAN_ENABLE_COMPONENT_DEPENDS ON)
set(CPACK_DEBIAN_PACKAGE_SECTION misc)
set(CPACK_DEBIAN_PACKAGE_CONTROL_STRICT_PERMISSION ON)
# gzip: a quarter of xz's time for the same packages (the package test runs in CI).
set(CPACK_DEBIAN_COMPRESSION_TYPE gzip)

set(CPACK_DEBIAN_DAEMON_PACKAGE_NAME rsud)
set(CPACK_DEBIAN_DAEMON_PACKAGE_SECTION net)
set(CPACK_DEBIAN_DAEMON_PACKAGE_RECOMMENDS "systemd, rsu-tools")
set(CPACK_DEBIAN_DAEMON_PACKAGE_CONTROL_EXTRA
    ${PROJECT_SOURCE_DIR}/deploy/debian/conffiles ${PROJECT_SOURCE_DIR}/deploy/debian/postinst
    ${PROJECT_SOURCE_DIR}/deploy/debian/postrm)
set(CPACK_DEBIAN_TOOLS_PACKAGE_NAME rsu-tools)
set(CPACK_DEBIAN_LIBRARY_PACKAGE_NAME librsu-vehicle-client${PROJECT_VERSION_MAJOR})
set(CPACK_DEBIAN_LIBRARY_PACKAGE_SECTION libs)
set(CPACK_DEBIAN_DEV_PACKAGE_NAME librsu-vehicle-client-dev)
set(CPACK_DEBIAN_DEV_PACKAGE_SECTION libdevel)
# Its headers include Eigen's and Boost.Asio's.
set(CPACK_DEBIAN_DEV_PACKAGE_DEPENDS "libeigen3-dev, libboost-dev")

include(CPack)
cpack_add_component(daemon DISPLAY_NAME rsud DESCRIPTION
                    "rsud: localizes connected vehicles with a roadside LiDAR and sends them signed corrections over V2I")
cpack_add_component(tools DISPLAY_NAME rsu-tools DESCRIPTION
                    "rsu-keygen, rsu-vehicle, rsu-sim, rsu-calibrate and the other rsu-localize programs")
cpack_add_component(library DISPLAY_NAME librsu-vehicle-client DESCRIPTION
                    "The vehicle side of rsu-localize's V2I as a shared library")
cpack_add_component(dev DISPLAY_NAME librsu-vehicle-client-dev DEPENDS library DESCRIPTION
                    "Headers, CMake package and pkg-config file of the rsu-localize vehicle client")
