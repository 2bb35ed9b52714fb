# Stages the developer-mode add-on and packs the zip, so that a Blender running from the build tree (the tests, under
# `ctest -j` beside a build) never sees the add-on half there. Run at build time:
#   cmake -DSRC=addon/firn -DINIT=__init__.py -DMODULE=firncore.so -DDEV_DIR=.../addons/firn -DSTAGE_ROOT=...
#         -DPACKAGE_DIR=.../package/firn -DZIP=firn.zip -P StageAddon.cmake
# DEV_DIR is a symbolic link to one of two trees in STAGE_ROOT (firn.a, firn.b): the build fills the other one and
# swaps the link with rename(2), which replaces it in one step. The link stays when the new tree equals the installed
# one, and the previous tree stays until the next swap, for a Blender that started before this one. The package is
# copied again every time (an edited .py changes no link); the zip is written beside itself and renamed over the old.
foreach(var SRC INIT MODULE DEV_DIR STAGE_ROOT PACKAGE_DIR ZIP)
  if(NOT DEFINED ${var})
    message(FATAL_ERROR "StageAddon.cmake needs -D${var}=...")
  endif()
endforeach()

file(GLOB_RECURSE files LIST_DIRECTORIES false RELATIVE ${SRC} ${SRC}/*.py ${SRC}/material/presets/*)
list(FILTER files EXCLUDE REGEX "(__pycache__|\\.pyc$)")

# Python sources are symlinked (edits are live without a rebuild); bl_info's __init__.py and the module are copied.
function(fill_tree tree)
  file(REMOVE_RECURSE ${tree})
  file(MAKE_DIRECTORY ${tree})
  foreach(rel IN LISTS files)
    get_filename_component(rel_dir ${rel} DIRECTORY)
    file(MAKE_DIRECTORY ${tree}/${rel_dir})
    file(CREATE_LINK ${SRC}/${rel} ${tree}/${rel} SYMBOLIC)
  endforeach()
  file(COPY ${INIT} ${MODULE} DESTINATION ${tree})
endfunction()

# What a staged file is: its link target, or its contents' hash.
function(file_id path result)
  if(IS_SYMLINK ${path})
    file(READ_SYMLINK ${path} id)
  else()
    file(SHA256 ${path} id)
  endif()
  set(${result} ${id} PARENT_SCOPE)
endfunction()

# The same files, the same link targets, the same contents (Python's __pycache__ aside).
function(same_tree a b result)
  set(${result} FALSE PARENT_SCOPE)
  foreach(tree a b)
    file(GLOB_RECURSE ${tree}_files LIST_DIRECTORIES false RELATIVE ${${tree}} ${${tree}}/*)
    list(FILTER ${tree}_files EXCLUDE REGEX "__pycache__")
    list(SORT ${tree}_files)
  endforeach()
  if(NOT a_files STREQUAL b_files)
    return()
  endif()
  foreach(rel IN LISTS a_files)
    file_id(${a}/${rel} a_id)
    file_id(${b}/${rel} b_id)
    if(NOT a_id STREQUAL b_id)
      return()
    endif()
  endforeach()
  set(${result} TRUE PARENT_SCOPE)
endfunction()

get_filename_component(dev_parent ${DEV_DIR} DIRECTORY)
set(installed "")
if(IS_SYMLINK ${DEV_DIR})
  file(READ_SYMLINK ${DEV_DIR} installed)
  get_filename_component(installed ${installed} ABSOLUTE BASE_DIR ${dev_parent})
endif()
if(installed STREQUAL "${STAGE_ROOT}/firn.a")
  set(next ${STAGE_ROOT}/firn.b)
else()
  set(next ${STAGE_ROOT}/firn.a)
endif()
fill_tree(${next})

set(unchanged FALSE)
if(EXISTS ${installed})
  same_tree(${installed} ${next} unchanged)
endif()
if(unchanged)
  file(REMOVE_RECURSE ${next})
else()
  file(RELATIVE_PATH target ${dev_parent} ${next})
  file(REMOVE ${STAGE_ROOT}/firn.link)
  file(CREATE_LINK ${target} ${STAGE_ROOT}/firn.link SYMBOLIC)
  if(EXISTS ${DEV_DIR} AND NOT IS_SYMLINK ${DEV_DIR})
    file(REMOVE_RECURSE ${DEV_DIR})  # a build tree from before the swap: its add-on was a plain folder
  endif()
  file(MAKE_DIRECTORY ${dev_parent})
  file(RENAME ${STAGE_ROOT}/firn.link ${DEV_DIR})
endif()

# The package holds real copies, zipped as users install them.
file(REMOVE_RECURSE ${PACKAGE_DIR})
foreach(rel IN LISTS files)
  get_filename_component(rel_dir ${rel} DIRECTORY)
  file(COPY ${SRC}/${rel} DESTINATION ${PACKAGE_DIR}/${rel_dir})
endforeach()
file(COPY ${INIT} ${MODULE} DESTINATION ${PACKAGE_DIR})
get_filename_component(package_parent ${PACKAGE_DIR} DIRECTORY)
get_filename_component(package_name ${PACKAGE_DIR} NAME)
execute_process(COMMAND ${CMAKE_COMMAND} -E tar cf ${ZIP}.part --format=zip ${package_name}
  WORKING_DIRECTORY ${package_parent} RESULT_VARIABLE tar_result)
if(NOT tar_result EQUAL 0)
  message(FATAL_ERROR "packing ${ZIP} failed")
endif()
file(RENAME ${ZIP}.part ${ZIP})
