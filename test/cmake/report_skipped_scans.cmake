# Says in one line how many tests the missing real scans left out: each test binary's "Real/" cases (the same
# tests run on the synthetic twins) and OTHER_TESTS more (the tools' and the README example's). BINARIES are
# separated by "|".
set(count ${OTHER_TESTS})
string(REPLACE "|" ";" binaries "${BINARIES}")
foreach(binary ${binaries})
  execute_process(COMMAND "${binary}" --gtest_list_tests "--gtest_filter=Real/*" OUTPUT_VARIABLE listing
                  RESULT_VARIABLE failed)
  if(failed)
    message(FATAL_ERROR "${binary} --gtest_list_tests failed")
  endif()
  string(REGEX MATCHALL "\n  [^\n]+" cases "\n${listing}")
  list(LENGTH cases n)
  math(EXPR count "${count} + ${n}")
endforeach()
message("Skipped ${count} tests on PCL's real scans (their synthetic twins ran): get kinect_capture0001-3.pcd, "
        "room_scan1-2.pcd and terrain_samp11.pcd from PCL's data repository as doc/user_guide.md says, then "
        "configure with PCL_FOT_DATA_DIR=<their directory> or put them in ../shared/data beside the repository.")
