# Runs a command that draws pictures into DIR, then checks each picture of PICTURES (comma-separated) is there,
# not empty, and not a single colour. Usage:
#   cmake -DDIR=<dir> -DPICTURES=<a.png,b.png> -P check_pictures.cmake -- <command that draws them into dir>
include("${CMAKE_CURRENT_LIST_DIR}/command_after_separator.cmake")
file(REMOVE_RECURSE "${DIR}")  # whatever is there afterwards, this run drew
execute_process(COMMAND ${cmd} RESULT_VARIABLE code OUTPUT_VARIABLE out ERROR_VARIABLE err)
if(NOT code EQUAL 0)
  message(FATAL_ERROR "exit code ${code}\nstdout:\n${out}\nstderr:\n${err}")
endif()
string(REPLACE "," ";" pictures "${PICTURES}")
foreach(picture ${pictures})
  set(file "${DIR}/${picture}")
  if(NOT EXISTS "${file}")
    message(FATAL_ERROR "${picture} was not drawn\nstdout:\n${out}\nstderr:\n${err}")
  endif()
  file(SIZE "${file}" size)
  # identify counts the distinct colours; a plot's anti-aliased text alone has dozens, a blank image one.
  execute_process(COMMAND identify -format "%k" "${file}" RESULT_VARIABLE code OUTPUT_VARIABLE colours
                  ERROR_VARIABLE err)
  if(size EQUAL 0 OR NOT code EQUAL 0 OR NOT colours GREATER 16)
    message(FATAL_ERROR "${picture}: ${size} bytes, ${colours} colours (identify: ${err})")
  endif()
  message(STATUS "${picture}: ${size} bytes, ${colours} colours")
endforeach()
