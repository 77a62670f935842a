# Layers that the build enforces. Includes are rooted at the repository ("common/core/math.hpp"),
# but no target sees the repository root: each library sees only its own folder, through a
# directory of links made here, plus what the libraries it links publicly see. An include that
# points up a layer (core -> transport, transport -> runtime, runtime -> dds) then fails to build.
function(qswarm_layer target)
  set(root ${PROJECT_BINARY_DIR}/layers/${target})
  foreach(dir IN LISTS ARGN)
    get_filename_component(parent ${root}/${dir} DIRECTORY)
    file(MAKE_DIRECTORY ${parent})
    if(NOT EXISTS ${root}/${dir})
      file(CREATE_LINK ${PROJECT_SOURCE_DIR}/${dir} ${root}/${dir} SYMBOLIC)
    endif()
  endforeach()
  get_target_property(type ${target} TYPE)
  if(type STREQUAL "INTERFACE_LIBRARY")
    target_include_directories(${target} INTERFACE $<BUILD_INTERFACE:${root}>)
  else()
    target_include_directories(${target} PUBLIC $<BUILD_INTERFACE:${root}>)
  endif()
endfunction()
