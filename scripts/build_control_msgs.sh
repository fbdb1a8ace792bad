#!/usr/bin/env bash
# Build the ROS 2 interface package control_msgs from source into a venv made from
# requirements-dev.txt, with colcon and PyPI's ros-jazzy-* wheels (no apt ROS, nothing sourced).
#
# Usage: scripts/build_control_msgs.sh VENV_DIR SOURCE_DIR REQUIREMENTS_FILE
#
#   VENV_DIR           an existing venv with ros-jazzy-rclpy etc. installed (e.g. .venv)
#   SOURCE_DIR         the control_msgs source tree (its package.xml and CMakeLists.txt)
#   REQUIREMENTS_FILE  the pinned build wheels (requirements-control-msgs.txt)
#
# Result: VENV_DIR/bin/python (and the console scripts in VENV_DIR/bin) can use
# control_msgs.{msg,srv,action} over rclpy with no setup file sourced and no LD_LIBRARY_PATH
# or AMENT_PREFIX_PATH set. Everything lands under VENV_DIR:
#   VENV_DIR/control_msgs/{build,install,log}   colcon's dirs (install is a merged prefix)
#   VENV_DIR/control_msgs/wheel_python_paths.cmake   fix for the wheels' exported cmake files
#   VENV_DIR/lib/libcontrol_msgs__*.so          symlinks to install/lib (where the wheels' libs are)
#   <site-packages>/control_msgs_colcon.pth     puts install's site-packages on sys.path
# Idempotent: exits 0 at once when control_msgs and its type support already load.
# Environment: MAKEFLAGS (default -j2); CONTROL_MSGS_CLEAN=1 deletes build/install first.
set -euo pipefail

say() { printf '[build_control_msgs] %s\n' "$*" >&2; }
die() { say "ERROR: $*"; exit 1; }

[ $# -eq 3 ] || die "usage: $0 VENV_DIR SOURCE_DIR REQUIREMENTS_FILE"
[ -x "$1/bin/python" ] || die "no venv at '$1' (missing $1/bin/python)"
[ -f "$2/package.xml" ] || die "no package.xml in SOURCE_DIR '$2'"
VENV=$(cd "$1" && pwd -P)
SRC=$(cd "$2" && pwd -P)
[ -f "$3" ] || die "requirements file '$3' not found"
REQS=$(cd "$(dirname "$3")" && pwd -P)/$(basename "$3")
PY=$VENV/bin/python
grep -q '<name>control_msgs</name>' "$SRC/package.xml" \
  || die "$SRC/package.xml is not the control_msgs package"

# Run the venv's python as a fresh process would see it: no sourced ROS, no hand-set paths.
clean_py() {
  env -u LD_LIBRARY_PATH -u AMENT_PREFIX_PATH -u PYTHONPATH -u COLCON_PREFIX_PATH \
    -u CMAKE_PREFIX_PATH -u _ROS_WHEELS_BOOTSTRAP_COMPLETE \
    ROS_DOMAIN_ID="${CONTROL_MSGS_CHECK_DOMAIN_ID:-87}" ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST \
    "$PY" "$@"
}
# Quick check: modules import and the C type support library loads (no DDS traffic).
CHECK_IMPORT='
from control_msgs.action import FollowJointTrajectory
from control_msgs.msg import SpeedScalingFactor, JointTolerance
for t in (FollowJointTrajectory, SpeedScalingFactor, JointTolerance):
    type(t).__import_type_support__()
    assert t._TYPE_SUPPORT is not None, t
'
# Full check: creating a publisher makes the rmw load the fastrtps type support library.
CHECK_RCLPY=$CHECK_IMPORT'
import rclpy
rclpy.init()
node = rclpy.create_node("build_control_msgs_check")
node.create_publisher(SpeedScalingFactor, "build_control_msgs_check", 1)
node.destroy_node()
rclpy.shutdown()
'

if [ "${CONTROL_MSGS_CLEAN:-0}" != 1 ] && clean_py -c "$CHECK_IMPORT" >/dev/null 2>&1; then
  say "control_msgs already usable in $VENV: nothing to do"
  exit 0
fi

# --- tools from the machine ------------------------------------------------------------------
for tool in cmake make cc c++; do
  command -v "$tool" >/dev/null || die "'$tool' not found: install cmake, make, gcc and g++"
done
CMAKE_VER=$(cmake --version | sed -n 's/^cmake version \([0-9]*\.[0-9]*\).*/\1/p')
printf '%s\n3.19\n' "$CMAKE_VER" | sort -V -C -r \
  || die "cmake >= 3.19 needed (have $CMAKE_VER)"
PYINC=$("$PY" -c 'import sysconfig; print(sysconfig.get_paths()["include"])')
[ -f "$PYINC/Python.h" ] || die "Python headers missing ($PYINC/Python.h): install the python dev package"

# --- build wheels ----------------------------------------------------------------------------
say "installing the build wheels into $VENV"
"$PY" -m pip install --disable-pip-version-check -q -r "$REQS"
"$PY" -c 'import ament_package, rosidl_generator_py, numpy' \
  || die "build wheels incomplete: ament_package / rosidl_generator_py / numpy do not import"

NUMPYINC=$("$PY" -c 'import numpy; print(numpy.get_include())')
SITE=$("$PY" -c 'import sysconfig; print(sysconfig.get_path("purelib"))')
WORK=$VENV/control_msgs
mkdir -p "$WORK"
if [ "${CONTROL_MSGS_CLEAN:-0}" = 1 ]; then
  say "CONTROL_MSGS_CLEAN=1: removing $WORK/build and $WORK/install"
  rm -rf "$WORK/build" "$WORK/install"
fi

# The wheels' exported cmake targets (<pkg>::<pkg>__rosidl_generator_py) carry their build
# machine's include dirs (/opt/python/cp3XX-cp3XX/include/python3.X and .../numpy/_core/include);
# CMake's generate step rejects non-existent include dirs of imported targets. This file,
# loaded after project() via CMAKE_PROJECT_INCLUDE, rewrites them on the imported targets at
# the end of the configure step; the installed wheel files stay untouched.
HOOK=$WORK/wheel_python_paths.cmake
cat > "$HOOK" <<'EOF'
# Written by build_control_msgs.sh. See there.
function(_cmsgs_fix_wheel_include_dirs)
  get_property(_targets DIRECTORY "${CMAKE_SOURCE_DIR}" PROPERTY IMPORTED_TARGETS)
  foreach(_t IN LISTS _targets)
    get_target_property(_inc ${_t} INTERFACE_INCLUDE_DIRECTORIES)
    if(NOT _inc OR NOT _inc MATCHES "(^|;)/opt/python/")
      continue()
    endif()
    set(_new "")
    foreach(_d IN LISTS _inc)
      if(_d MATCHES "^/opt/python/[^/]+/include/python")
        list(APPEND _new "${CMSGS_PYTHON_INCLUDE_DIR}")
      elseif(_d MATCHES "^/opt/python/.*/numpy/.*include")
        list(APPEND _new "${CMSGS_NUMPY_INCLUDE_DIR}")
      elseif(_d MATCHES "^/opt/python/" AND NOT EXISTS "${_d}")
        # another path of the wheels' build machine: drop it
      else()
        list(APPEND _new "${_d}")
      endif()
    endforeach()
    list(REMOVE_DUPLICATES _new)
    set_target_properties(${_t} PROPERTIES INTERFACE_INCLUDE_DIRECTORIES "${_new}")
  endforeach()
endfunction()
cmake_language(DEFER DIRECTORY "${CMAKE_SOURCE_DIR}" CALL _cmsgs_fix_wheel_include_dirs)
EOF

# --- colcon build ------------------------------------------------------------------------------
say "building $SRC with colcon (build/install/log under $WORK); takes a few minutes"
start=$(date +%s)
# Only the venv is a prefix: a sourced ROS install must not leak into the build. AMENT_PREFIX_PATH
# is needed (the rosidl cmake code looks its typesupports up in the ament index); colcon warns
# that the venv has no local_setup.* files: harmless.
# RPATH: $ORIGIN for the libs in install/lib, $ORIGIN/../../.. for the Python extensions in
# install/lib/pythonX.Y/site-packages/control_msgs (both resolve to install/lib).
(
  cd "$WORK"
  env -u LD_LIBRARY_PATH -u PYTHONPATH -u COLCON_PREFIX_PATH -u _ROS_WHEELS_BOOTSTRAP_COMPLETE \
    PATH="$VENV/bin:$PATH" CMAKE_PREFIX_PATH="$VENV" AMENT_PREFIX_PATH="$VENV" \
    MAKEFLAGS="${MAKEFLAGS:--j2}" \
    "$VENV/bin/colcon" --log-base "$WORK/log" build \
      --base-paths "$SRC" --packages-select control_msgs \
      --build-base "$WORK/build" --install-base "$WORK/install" --merge-install \
      --parallel-workers 1 --event-handlers desktop_notification- \
      --cmake-args \
        -DBUILD_TESTING=OFF -DCMAKE_BUILD_TYPE=Release \
        "-DPython3_EXECUTABLE=$PY" "-DPYTHON_EXECUTABLE=$PY" \
        "-DCMAKE_PROJECT_INCLUDE=$HOOK" \
        "-DCMSGS_PYTHON_INCLUDE_DIR=$PYINC" "-DCMSGS_NUMPY_INCLUDE_DIR=$NUMPYINC" \
        '-DCMAKE_INSTALL_RPATH=$ORIGIN;$ORIGIN/../../..'
) || die "colcon build failed: see the output above and $WORK/log/latest_build"
say "built in $(( $(date +%s) - start )) s"

INSTALL=$WORK/install
PYDIR=$(cd "$INSTALL" && ls -d lib/python3*/site-packages 2>/dev/null | head -1)
[ -n "$PYDIR" ] && [ -d "$INSTALL/$PYDIR/control_msgs" ] \
  || die "no control_msgs Python package under $INSTALL/lib/python3*/site-packages"
ls "$INSTALL"/lib/libcontrol_msgs__rosidl_typesupport_fastrtps_c.so >/dev/null \
  || die "type support libraries missing from $INSTALL/lib"

# --- make it found -----------------------------------------------------------------------------
# How the ros-* wheels find their own libs: they have no RPATH; ros_wheels_bootstrapper.pth
# re-executes the interpreter once with LD_LIBRARY_PATH = VENV/lib + site-packages/ros_*.libs.
# rosidl_typesupport_c dlopen()s the per-package type support libraries by bare name
# (libcontrol_msgs__rosidl_typesupport_fastrtps_c.so), which only LD_LIBRARY_PATH resolves.
# So the libs go next to the wheels' own libs: relative symlinks VENV/lib/libcontrol_msgs__*.so
# -> ../control_msgs/install/lib/. (RUNPATH $ORIGIN above resolves the libs' links among
# themselves.) Python: a .pth puts install's site-packages on sys.path.
find "$VENV/lib" -maxdepth 1 -name 'libcontrol_msgs__*.so' -type l -delete
for lib in "$INSTALL"/lib/libcontrol_msgs__*.so; do
  ln -sf "../control_msgs/install/lib/$(basename "$lib")" "$VENV/lib/$(basename "$lib")"
done
PTH=$SITE/control_msgs_colcon.pth
printf '%s\n' "$INSTALL/$PYDIR" > "$PTH"
say "linked $(ls "$INSTALL"/lib/libcontrol_msgs__*.so | wc -l) libraries into $VENV/lib; wrote $PTH"

clean_py -c "$CHECK_RCLPY" || die "control_msgs built but does not load over rclpy (see above)"
say "OK: control_msgs is usable from $PY"
