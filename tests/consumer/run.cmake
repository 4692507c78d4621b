# Installs the build tree into a scratch prefix, runs the installed `rastercheck` from there, then
# configures, builds and runs two projects against that prefix: the consumer beside this script,
# and the README's "Using it from C++" section as a user copies it (its ```cmake block is the
# CMakeLists.txt, each ```cpp block the file its first line names). The shared data (Panda) is
# used when RASTERCHECK_DATA, else DATA_DIR, holds it; the crane and an OMPL.app problem written here need nothing else.
# Arguments: BUILD_DIR, SOURCE_DIR (this folder), REPO_DIR, WORK_DIR, DATA_DIR, LAUNCHER (optional).
cmake_minimum_required(VERSION 3.22)  # policies: while(TRUE), if(MATCHES) on variables
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
    run("${name}: build" ${CMAKE_COMMAND} --build ${WORK_DIR}/${name}-build --parallel 2)
endfunction()

run("install" ${CMAKE_COMMAND} --install ${BUILD_DIR} --prefix ${prefix})
set(crane ${REPO_DIR}/robots/crane)
run("installed rastercheck" ${prefix}/bin/rastercheck info ${crane}/crane.urdf --srdf ${crane}/crane.srdf)
if(NOT output MATCHES "components")
    message(FATAL_ERROR "installed rastercheck info printed no components")
endif()

build_project(consumer ${SOURCE_DIR})
run("consumer" ${WORK_DIR}/consumer-build/consumer)

# ---- the README's C++ section, block by block ----
file(READ ${REPO_DIR}/README.md readme)
string(FIND "${readme}" "## Using it from C++" begin)
if(begin EQUAL -1)
    message(FATAL_ERROR "README.md has no '## Using it from C++' section")
endif()
string(SUBSTRING "${readme}" ${begin} -1 section)
string(FIND "${section}" "\n## " end)
string(SUBSTRING "${section}" 0 ${end} section)
set(readme_dir ${WORK_DIR}/readme)
set(blocks 0)
while(TRUE)
    string(FIND "${section}" "\n```c" open)
    if(open EQUAL -1)
        break()
    endif()
    math(EXPR open "${open} + 4")
    string(SUBSTRING "${section}" ${open} -1 section)
    string(FIND "${section}" "\n" eol)
    string(SUBSTRING "${section}" 0 ${eol} language)
    math(EXPR eol "${eol} + 1")
    string(SUBSTRING "${section}" ${eol} -1 section)
    string(FIND "${section}" "\n```" close)
    string(SUBSTRING "${section}" 0 ${close} body)
    math(EXPR close "${close} + 4")
    string(SUBSTRING "${section}" ${close} -1 section)
    if(language STREQUAL "cmake")
        set(file CMakeLists.txt)
    elseif(language STREQUAL "cpp" AND body MATCHES "^// ([A-Za-z_]+\\.cpp)\n")
        set(file ${CMAKE_MATCH_1})
    else()
        message(FATAL_ERROR "README.md, '${language}' block without a file name (its first line: // NAME.cpp)")
    endif()
    file(WRITE ${readme_dir}/${file} "${body}\n")
    math(EXPR blocks "${blocks} + 1")
endwhile()
if(NOT blocks EQUAL 3 OR NOT EXISTS ${readme_dir}/CMakeLists.txt)
    message(FATAL_ERROR "README.md's C++ section: expected CMakeLists.txt, check_states.cpp and plan.cpp, found ${blocks} blocks")
endif()
build_project(readme ${readme_dir})
set(bin ${WORK_DIR}/readme-build)

run("check_states crane" ${bin}/check_states ${crane}/crane.urdf ${crane}/crane.srdf ${REPO_DIR}/robots/sites/plant.yaml)
if(NOT output MATCHES "neutral: (in)?valid\n[0-9]+ of 10000 random states invalid")
    message(FATAL_ERROR "check_states printed no verdicts")
endif()

# An OMPL.app problem: a 10 cm cube to move past a 1 m block.
set(cfg_dir ${WORK_DIR}/cfg)
function(obj_box path x0 y0 z0 x1 y1 z1)
    file(WRITE ${path} "v ${x0} ${y0} ${z0}\nv ${x1} ${y0} ${z0}\nv ${x1} ${y1} ${z0}\nv ${x0} ${y1} ${z0}\n"
        "v ${x0} ${y0} ${z1}\nv ${x1} ${y0} ${z1}\nv ${x1} ${y1} ${z1}\nv ${x0} ${y1} ${z1}\n"
        "f 1 4 3\nf 1 3 2\nf 5 6 7\nf 5 7 8\nf 1 2 6\nf 1 6 5\nf 4 8 7\nf 4 7 3\nf 1 5 8\nf 1 8 4\nf 2 3 7\nf 2 7 6\n")
endfunction()
obj_box(${cfg_dir}/robot.obj -0.05 -0.05 -0.05 0.05 0.05 0.05)
obj_box(${cfg_dir}/world.obj -0.5 -0.5 -0.5 0.5 0.5 0.5)
set(pose ".y = 0\n.z = 0\n.theta = 0\n.axis.x = 1\n.axis.y = 0\n.axis.z = 0\n")
string(REPLACE "\n." "\nstart." start_pose "\n${pose}")
string(REPLACE "\n." "\ngoal." goal_pose "\n${pose}")
file(WRITE ${cfg_dir}/problem.cfg "[problem]\nname = block\nrobot = robot.obj\nworld = world.obj\nstart.x = -1.5"
    "${start_pose}goal.x = 1.5${goal_pose}"
    "volume.min.x = -2\nvolume.min.y = -2\nvolume.min.z = -2\nvolume.max.x = 2\nvolume.max.y = 2\nvolume.max.z = 2\n")
run("plan problem.cfg" ${bin}/plan ${cfg_dir}/problem.cfg)
if(NOT output MATCHES "path of [0-9]+ states")
    message(FATAL_ERROR "plan printed no path")
endif()

if(DEFINED ENV{RASTERCHECK_DATA})
    set(DATA_DIR $ENV{RASTERCHECK_DATA})
endif()
set(panda ${DATA_DIR}/mbm/panda)
if(EXISTS ${panda}/panda.urdf)
    set(box ${panda}/problems/box_panda)
    run("check_states panda" ${bin}/check_states ${panda}/panda.urdf ${panda}/panda.srdf ${box}/scene0001.yaml)
    run("plan panda" ${bin}/plan ${panda}/panda.urdf ${panda}/panda.srdf ${box}/scene0001.yaml ${box}/request0001.yaml)
else()
    message(STATUS "shared data not found (${DATA_DIR}): the README programs ran on the crane and problem.cfg only")
endif()
