# The command a -P script runs: its arguments after "--", in `cmd` (included by expect_run.cmake and
# check_pictures.cmake).
set(cmd)
set(after_separator OFF)
foreach(i RANGE 1 ${CMAKE_ARGC})
  if(after_separator AND DEFINED CMAKE_ARGV${i})
    list(APPEND cmd "${CMAKE_ARGV${i}}")
  elseif("${CMAKE_ARGV${i}}" STREQUAL "--")
    set(after_separator ON)
  endif()
endforeach()
