# Run by ctest (see CMakeLists.txt): installs the runtime component of BUILD_DIR under WORK_DIR/prefix, then
# configures, builds and runs the consumer project in SOURCE_DIR against that prefix alone, and checks with ldd that
# the consumer loads none of the heavy libraries the thin runtime must not need.
file(REMOVE_RECURSE ${WORK_DIR})

function(run step)
  execute_process(COMMAND ${ARGN} RESULT_VARIABLE result OUTPUT_VARIABLE output ERROR_VARIABLE output)
  if(NOT result EQUAL 0)
    message(FATAL_ERROR "${step} failed (${result}):\n${output}")
  endif()
  message(STATUS "${step}: ok")
endfunction()

run(install ${CMAKE_COMMAND} --install ${BUILD_DIR} --prefix ${WORK_DIR}/prefix --component prt_runtime)
set(launcher)
if(COMPILER_LAUNCHER)
  set(launcher -DCMAKE_CXX_COMPILER_LAUNCHER=${COMPILER_LAUNCHER})
endif()
run(configure ${CMAKE_COMMAND} -S ${SOURCE_DIR} -B ${WORK_DIR}/build -G ${GENERATOR} -DCMAKE_BUILD_TYPE=Release
    -DCMAKE_CXX_COMPILER=${CXX_COMPILER} ${launcher} -DCMAKE_PREFIX_PATH=${WORK_DIR}/prefix
    -DEXPECTED_PRT_DIR=${WORK_DIR}/prefix/lib/cmake/prt)
run(build ${CMAKE_COMMAND} --build ${WORK_DIR}/build)
run(relight ${WORK_DIR}/build/consumer ${WORK_DIR}/consumer.glb)
# The -fno-exceptions consumer: the bundle the first one wrote, a missing file, and that bundle cut in half.
file(SIZE ${WORK_DIR}/consumer.glb bundle_bytes)
math(EXPR half "${bundle_bytes} / 2")
execute_process(COMMAND head -c ${half} ${WORK_DIR}/consumer.glb OUTPUT_FILE ${WORK_DIR}/truncated.glb)
run(relight_nothrow ${WORK_DIR}/build/consumer_nothrow ${WORK_DIR}/consumer.glb ${WORK_DIR}/absent.glb
    ${WORK_DIR}/truncated.glb)
# Headers install under include/prt/ and nothing of prt sits directly in include/, so none shadows an engine's.
file(GLOB flat_headers ${WORK_DIR}/prefix/include/*.h)
if(flat_headers)
  message(FATAL_ERROR "headers installed outside include/prt/: ${flat_headers}")
endif()
if(EXISTS ${WORK_DIR}/prefix/include/prt/core.h)
  message(FATAL_ERROR "core.h (logging, kill hooks) is installed; the runtime's headers must not need it")
endif()

# The thin runtime's promise: the consumer needs the C++ standard library and tinygltf, nothing of the rest of prt.
execute_process(COMMAND ldd ${WORK_DIR}/build/consumer RESULT_VARIABLE result OUTPUT_VARIABLE libraries
                ERROR_VARIABLE libraries)
if(NOT result EQUAL 0)
  message(FATAL_ERROR "ldd failed (${result}):\n${libraries}")
endif()
foreach(forbidden OpenImageIO tbb embree ceres OpenCL OpenEXR xxhash)
  string(TOLOWER "${libraries}" lower)
  string(TOLOWER "${forbidden}" name)
  if(lower MATCHES "lib${name}")
    message(FATAL_ERROR "the consumer loads ${forbidden}:\n${libraries}")
  endif()
endforeach()
string(REGEX MATCHALL "\n" lines "\n${libraries}")
list(LENGTH lines count)
file(SIZE ${WORK_DIR}/build/consumer bytes)
message(STATUS "ldd: ${count} lines, none of OpenImageIO, TBB, Embree, Ceres, OpenCL, OpenEXR, xxhash; consumer ${bytes} bytes")
