# Installs the build tree into a scratch prefix, runs the installed `rastercheck` from there, then
# configures, builds and runs the consumer beside this script against that prefix.
# Arguments: BUILD_DIR, SOURCE_DIR (this folder), REPO_DIR, WORK_DIR, LAUNCHER (optional).
file(REMOVE_RECURSE ${WORK_DIR})
set(prefix ${WORK_DIR}/prefix)

# Runs a command with no LD_LIBRARY_PATH (the installed programs must find their libraries by
# themselves) and fails the test when it fails; its output is printed for ctest's log.
function(run what)
    execute_process(COMMAND ${CMAKE_COMMAND} -E env --unset=LD_LIBRARY_PATH ${ARGN}
        RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
    message(STATUS "${what}:\n${out}${err}")
    if(rc)
        message(FATAL_ERROR "${what} failed: ${rc}")
    endif()
    set(output "${out}" PARENT_SCOPE)
endfunction()

set(launcher "")
if(LAUNCHER)
    set(launcher -DCMAKE_CXX_COMPILER_LAUNCHER=${LAUNCHER})
endif()
function(build_project name source)
    run("${name}: configure" ${CMAKE_COMMAND} -S ${source} -B ${WORK_DIR}/${name}-build -DCMAKE_PREFIX_PATH=${prefix}
        -DCMAKE_BUILD_TYPE=Release ${launcher})
    run("${name}: build" ${CMAKE_COMMAND} --build ${WORK_DIR}/${name}-build)
endfunction()

run("install" ${CMAKE_COMMAND} --install ${BUILD_DIR} --prefix ${prefix})
set(crane ${REPO_DIR}/robots/crane)
run("installed rastercheck" ${prefix}/bin/rastercheck info ${crane}/crane.urdf --srdf ${crane}/crane.srdf)
if(NOT output MATCHES "components")
    message(FATAL_ERROR "installed rastercheck info printed no components")
endif()

build_project(consumer ${SOURCE_DIR})
run("consumer" ${WORK_DIR}/consumer-build/consumer)
