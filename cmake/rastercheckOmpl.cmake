# OMPL 1.5 ships a config with variables only. Wrap them in an interface target so that both our
# build and consumers of the installed package link one name. OMPL_LIBRARIES names unversioned
# boost libraries, which the boost -dev packages (see scripts/install-deps.sh) provide.
if(NOT TARGET rastercheck_ompl_deps)
    if(NOT OMPL_FOUND)
        find_package(ompl REQUIRED)
    endif()
    add_library(rastercheck_ompl_deps INTERFACE)
    target_include_directories(rastercheck_ompl_deps SYSTEM INTERFACE ${OMPL_INCLUDE_DIRS})
    target_link_libraries(rastercheck_ompl_deps INTERFACE ${OMPL_LIBRARIES})
endif()
