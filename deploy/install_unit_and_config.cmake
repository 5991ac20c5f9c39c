# SPDX-License-Identifier: Apache-2.0
# Run by `cmake --install` (and CPack) for the daemon component: installs rsud's example configuration
# and its systemd unit with the paths of this installation. The configuration directory follows
# GNUInstallDirs: /etc for the prefixes / and /usr (a Debian package), /etc/opt/... for /opt/...,
# <prefix>/etc otherwise. Set by the install(CODE) before it: RSUD_DEPLOY_DIR (deploy/ in the source
# tree), RSUD_WORK_DIR (a folder of the build tree), RSUD_SBINDIR and RSUD_SYSTEMD_UNIT_DIR (relative
# to the prefix).
set(prefix "${CMAKE_INSTALL_PREFIX}")
if(prefix STREQUAL "/" OR prefix STREQUAL "/usr")
  set(CMAKE_INSTALL_FULL_SYSCONFDIR "/etc")
elseif(prefix MATCHES "^/opt/")
  set(CMAKE_INSTALL_FULL_SYSCONFDIR "/etc${prefix}")
else()
  set(CMAKE_INSTALL_FULL_SYSCONFDIR "${prefix}/etc")
endif()
set(CMAKE_INSTALL_FULL_SBINDIR "${prefix}/${RSUD_SBINDIR}")
if(prefix STREQUAL "/")
  set(CMAKE_INSTALL_FULL_SBINDIR "/${RSUD_SBINDIR}")
endif()
# file(INSTALL) adds $DESTDIR itself and records the files in the install manifest.
file(INSTALL DESTINATION "${CMAKE_INSTALL_FULL_SYSCONFDIR}/rsud" TYPE FILE
     FILES "${RSUD_DEPLOY_DIR}/rsud.yaml" "${RSUD_DEPLOY_DIR}/cyclonedds-loopback.xml")
# One unit file per destination: installs into two prefixes may run at once (ctest -j).
string(MD5 destination "$ENV{DESTDIR}${prefix}")
set(unit_dir "${RSUD_WORK_DIR}/${destination}")
configure_file("${RSUD_DEPLOY_DIR}/rsud.service" "${unit_dir}/rsud.service" @ONLY)
file(INSTALL DESTINATION "${prefix}/${RSUD_SYSTEMD_UNIT_DIR}" TYPE FILE FILES "${unit_dir}/rsud.service")
