# Hostile input for the tools, a class of defect at a time (doc/reliability.md): no crash, no hang, no file of
# the user's changed, no exit 0 on nonsense. Included by test/CMakeLists.txt, which defines tool_test.
set(h "${runs}/hostile")
file(REMOVE_RECURSE "${h}")
file(MAKE_DIRECTORY "${h}" "${h}/data")
set(cloud_text "VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH 4\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS 4\nDATA ascii\n1 0 0\n0 1 0\n0 0 1\n1 1 1\n")
file(WRITE "${h}/c.pcd" "${cloud_text}")
file(WRITE "${h}/m_occupied.pcd" "${cloud_text}")
file(WRITE "${h}/m.fot" "0 0 0 1 0 0 0\n")  # a pose file named like fot_map's map
file(CREATE_LINK "${h}/c.pcd" "${h}/link_to_c.pcd" SYMBOLIC)
foreach(scan kinect_capture0001 kinect_capture0002 kinect_capture0003 room_scan1 room_scan2 terrain_samp11)
  file(WRITE "${h}/data/${scan}.pcd" "${cloud_text}")
endforeach()
set(cloud_files "${h}/c.pcd;${h}/link_to_c.pcd;${h}/m_occupied.pcd;${h}/m.fot;${h}/data/room_scan1.pcd")

# 1. An output is never an input, however it is spelt: by name, through ./ or a link, or named like an output.
tool_test(Hostile.OutputIsInput.SameName COMMAND $<TARGET_FILE:fot_convert> "${h}/c.pcd" "${h}/c.pcd" -res 0.1
          EXIT 1 ONE_LINE_ERROR MATCH "is the input" UNCHANGED ${cloud_files})
tool_test(Hostile.OutputIsInput.DotSlash COMMAND $<TARGET_FILE:fot_convert> "${h}/c.pcd" "${h}/./c.pcd" -res 0.1
          EXIT 1 ONE_LINE_ERROR MATCH "is the input" UNCHANGED ${cloud_files})
tool_test(Hostile.OutputIsInput.ThroughALink COMMAND $<TARGET_FILE:fot_convert> "${h}/c.pcd" "${h}/link_to_c.pcd"
          -res 0.1 EXIT 1 ONE_LINE_ERROR MATCH "is the input" UNCHANGED ${cloud_files})
tool_test(Hostile.OutputIsInput.ScanNamedLikeAnOutput COMMAND $<TARGET_FILE:fot_map> -res 0.1 "${h}/m_occupied.pcd"
          -out "${h}/m" EXIT 1 ONE_LINE_ERROR MATCH "is the input" UNCHANGED ${cloud_files})
tool_test(Hostile.OutputIsInput.PoseFileNamedLikeTheMap COMMAND $<TARGET_FILE:fot_map> -poses "${h}/m.fot"
          "${h}/c.pcd" -out "${h}/m" EXIT 1 ONE_LINE_ERROR MATCH "is the input" UNCHANGED ${cloud_files})
if(TARGET fot_bench)
  tool_test(Hostile.OutputIsInput.BenchmarkOverAScan COMMAND $<TARGET_FILE:fot_bench> -data "${h}/data"
            -out "${h}/data/room_scan1.pcd" EXIT 1 ONE_LINE_ERROR MATCH "is the input" UNCHANGED ${cloud_files})
endif()

# 2. A target that is not a regular file is written into, never replaced; a link's file is replaced, not the link.
file(CREATE_LINK /dev/null "${h}/null.fot" SYMBOLIC)
file(CREATE_LINK /dev/full "${h}/full.fot" SYMBOLIC)
tool_test(Hostile.Device.NullStaysADevice COMMAND $<TARGET_FILE:fot_convert> "${h}/c.pcd" "${h}/null.fot" -res 0.1
          MATCH "Wrote" UNCHANGED "/dev/null;${h}/null.fot")
tool_test(Hostile.Device.FullIsAnError COMMAND $<TARGET_FILE:fot_convert> "${h}/c.pcd" "${h}/full.fot" -res 0.1
          EXIT 2 ONE_LINE_ERROR MATCH "No space left on device" UNCHANGED "/dev/full;${h}/full.fot")
file(WRITE "${h}/real.fot" "old")
file(CREATE_LINK "${h}/real.fot" "${h}/link.fot" SYMBOLIC)
tool_test(Hostile.Device.ALinkedFileIsReplacedNotTheLink COMMAND $<TARGET_FILE:fot_convert> "${h}/c.pcd"
          "${h}/link.fot" -res 0.1 MATCH "Wrote" UNCHANGED "${h}/link.fot;${h}/c.pcd")

# 3. Every value is checked at the precision it is used in: these are finite doubles and infinite floats.
tool_test(Hostile.FloatRange.IcpGuess COMMAND $<TARGET_FILE:fot_icp_psi> "${h}/c.pcd" "${h}/c.pcd"
          -guess 1e39,0,0,0 EXIT 1 ONE_LINE_ERROR MATCH "-guess .*float's range")
tool_test(Hostile.FloatRange.IcpLeaf COMMAND $<TARGET_FILE:fot_icp_psi> "${h}/c.pcd" "${h}/c.pcd" -leaf 1e39
          EXIT 1 ONE_LINE_ERROR MATCH "-leaf .*float's range")
tool_test(Hostile.FloatRange.PsiTransform COMMAND $<TARGET_FILE:fot_psi> "${h}/c.pcd" "${h}/c.pcd"
          -transform 0,0,0,0,0,-1e39 EXIT 1 ONE_LINE_ERROR MATCH "-transform .*float's range")

# 4. ψ of nothing, or of a remnant, is no score.
tool_test(Hostile.PsiOfNothing.EveryPointDropped COMMAND $<TARGET_FILE:fot_psi> "${data}/room_scan1.pcd"
          "${data}/room_scan2.pcd" -res 1e-9 EXIT 2 MATCH "keeps [0-9]+ of its [0-9]+ finite points")
tool_test(Hostile.PsiOfNothing.AnEmptyCloud COMMAND $<TARGET_FILE:fot_psi> "${runs}/empty.pcd" "${h}/c.pcd"
          EXIT 2 ONE_LINE_ERROR MATCH "has no occupied cell: there is nothing to compare")
# CMake drops empty arguments from a command: a shell passes them.
tool_test(Hostile.PsiOfNothing.AnEmptyCap COMMAND sh -c "$<TARGET_FILE:fot_psi> ${h}/c.pcd ${h}/c.pcd -cap ''"
          EXIT 1 ONE_LINE_ERROR MATCH "option -cap needs a value, and it is empty")

# 5. One option parser: empty, repeated and unknown values, and stray arguments, with the usage line.
tool_test(Hostile.Options.EmptyThreads COMMAND sh -c "$<TARGET_FILE:fot_psi> ${h}/c.pcd ${h}/c.pcd -threads ''"
          EXIT 1 ONE_LINE_ERROR MATCH "-threads needs a value, and it is empty.*usage: fot_psi a b")
tool_test(Hostile.Options.EmptyLeaf COMMAND sh -c "$<TARGET_FILE:fot_icp_psi> ${h}/c.pcd ${h}/c.pcd -leaf ''"
          EXIT 1 ONE_LINE_ERROR MATCH "-leaf needs a value, and it is empty")
tool_test(Hostile.Options.MissingValue COMMAND $<TARGET_FILE:fot_psi> "${h}/c.pcd" "${h}/c.pcd" -cap
          EXIT 1 ONE_LINE_ERROR MATCH "option -cap needs a value \\(usage")
tool_test(Hostile.Options.RepeatedWithABadSecond COMMAND $<TARGET_FILE:fot_convert> "${h}/c.pcd" "${h}/x.fot"
          -res 0.1 -res abc EXIT 1 ONE_LINE_ERROR MATCH "option -res is given twice" ABSENT "${h}/x.fot")
tool_test(Hostile.Options.RepeatedWithANegativeSecond COMMAND $<TARGET_FILE:fot_map> -res 0.1 -res -5
          EXIT 1 ONE_LINE_ERROR MATCH "option -res is given twice")
tool_test(Hostile.Options.NegativeThreads COMMAND $<TARGET_FILE:fot_map> -threads -2 -out "${h}/t"
          EXIT 1 ONE_LINE_ERROR MATCH "option -threads must not be negative" ABSENT "${h}/t.fot")
tool_test(Hostile.Options.NumberWithTrailingText COMMAND $<TARGET_FILE:fot_map> -res 0.1m
          EXIT 1 ONE_LINE_ERROR MATCH "option -res needs a finite number")
tool_test(Hostile.Options.StrayArgument COMMAND $<TARGET_FILE:fot_convert> "${h}/c.pcd" "${h}/y.fot" "${h}/z.fot"
          -res 0.1 EXIT 1 ONE_LINE_ERROR MATCH "unexpected argument '.*z.fot'" ABSENT "${h}/y.fot;${h}/z.fot")
if(TARGET fot_bench)
  tool_test(Hostile.Options.UnknownSection COMMAND $<TARGET_FILE:fot_bench> -data "${h}/data" -out "${h}/b.md"
            -sections serch EXIT 1 ONE_LINE_ERROR MATCH "'serch' is none of" ABSENT "${h}/b.md")
  tool_test(Hostile.Options.BenchStrayArgument COMMAND $<TARGET_FILE:fot_bench> -data "${h}/data" -out "${h}/b.md"
            extra EXIT 1 ONE_LINE_ERROR MATCH "unexpected argument 'extra'" ABSENT "${h}/b.md")
endif()

# 7. Advice that can work: a resolution too fine for the cloud is named, not an origin.
tool_test(Hostile.Advice.ResolutionTooFine COMMAND $<TARGET_FILE:fot_convert> "${data}/room_scan1.pcd" "${h}/fine.fot"
          -res 1e-12 MATCH "coarser -res")

# A cloud just wider than 2^29 cells of 0.5 nm either side of 0: the origin named is its centre on the grid,
# without "-0", and it holds every point.
file(WRITE "${h}/narrow.pcd" "VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH 2\nHEIGHT 1\nPOINTS 2\nDATA ascii\n-0.4 0 0\n0 0 0\n")
tool_test(Hostile.Advice.OriginOnTheGrid COMMAND $<TARGET_FILE:fot_convert> "${h}/narrow.pcd" "${h}/narrow.fot" -res 5e-10
          MATCH "1 points lie beyond .* -origin -0[.]2[0-9]*,0,0\n")
tool_test(Hostile.Advice.TheNamedOriginHoldsEveryPoint COMMAND $<TARGET_FILE:fot_convert> "${h}/narrow.pcd"
          "${h}/narrow_centred.fot" -res 5e-10 -origin -0.200000003,0,0 MATCH "Inserted 2 points \\(skipped 0 NaN/Inf, 0 out of range\\)")

# 8. A temporary file left by a killed writer is removed by the next write of the same target.
file(WRITE "${h}/.kept.fot.pcl_fot-tmp.2147483646.0" "left by a killed writer")
file(WRITE "${h}/.other.fot.pcl_fot-tmp.2147483646.0" "another target's")
tool_test(Hostile.Leftovers.StaleTemporaryIsRemoved COMMAND $<TARGET_FILE:fot_convert> "${h}/c.pcd" "${h}/kept.fot"
          -res 0.1 MATCH "Wrote" ABSENT "${h}/.kept.fot.pcl_fot-tmp.2147483646.0"
          UNCHANGED "${h}/.other.fot.pcl_fot-tmp.2147483646.0")
# A writer that is still alive (process 1 always is) keeps its temporary file.
file(WRITE "${h}/.busy.fot.pcl_fot-tmp.1.0" "being written")
tool_test(Hostile.Leftovers.ALiveWritersTemporaryStays COMMAND $<TARGET_FILE:fot_convert> "${h}/c.pcd" "${h}/busy.fot"
          -res 0.1 MATCH "Wrote" UNCHANGED "${h}/.busy.fot.pcl_fot-tmp.1.0")
# fot_map's outputs are replaced one by one: each whole, the map first.
tool_test(Hostile.Leftovers.EveryOutputWhole COMMAND $<TARGET_FILE:fot_map> -res 0.1 "${h}/c.pcd" -out "${h}/whole"
          MATCH "Wrote .*whole.fot .*whole_occupied.pcd .*whole_mesh.vtk")

# 6. A few bytes cost what they hold: OctoMap's nodes are ours, so a pruned leaf at depth 2 (a cube of 16384
# cells a side) or a root that is a leaf is one word; off OctoMap's grid the size it would need is named at once.
set(bt_leaf "${PROJECT_SOURCE_DIR}/test/data/hostile/one_pruned_leaf.bt")
set(ot_root "${PROJECT_SOURCE_DIR}/test/data/hostile/root_leaf.ot")
tool_test(Hostile.Cost.PrunedLeafAtDepthTwo COMMAND $<TARGET_FILE:fot_info> "${bt_leaf}"
          MATCH "occupied cells +4398046511104\n +free cells +0\n +settled cells +4398046511104 .*\n +unsettled cells +0 .*\n +node words +1 in 0 blocks")
# Its log-odds, 0.85, lies between the clamps: a cube of one value, one word as well.
tool_test(Hostile.Cost.RootThatIsALeaf COMMAND $<TARGET_FILE:fot_info> "${ot_root}"
          MATCH "unsettled cells +281474976710656 .*in 1 words.*\n +node words +1 in 0 blocks")
tool_test(Hostile.Cost.CubeToFot COMMAND $<TARGET_FILE:fot_convert> "${bt_leaf}" "${h}/cube.fot" SETUP hostile_cube
          MATCH "Wrote .*cube.fot")
tool_test(Hostile.Cost.CubeBackToOctoMap COMMAND $<TARGET_FILE:fot_convert> "${h}/cube.fot" "${h}/cube.bt"
          REQUIRES hostile_cube MATCH "Wrote .*cube.bt")
add_test(NAME Tool.Hostile.Cost.CubeRoundTripIsTheFile COMMAND ${CMAKE_COMMAND} -E compare_files "${bt_leaf}" "${h}/cube.bt")
set_tests_properties(Tool.Hostile.Cost.CubeRoundTripIsTheFile PROPERTIES DEPENDS Tool.Hostile.Cost.CubeBackToOctoMap
                     FIXTURES_REQUIRED hostile_cube)
tool_test(Hostile.Cost.OffGridOriginIsRefusedAtOnce COMMAND $<TARGET_FILE:fot_convert> "${bt_leaf}" "${h}/moved.fot"
          -origin 0.05,0,0 EXIT 2 ONE_LINE_ERROR MATCH "would need up to 2.51e\\+09 bytes .*-max_memory" ABSENT "${h}/moved.fot")
# The same cube in a map whose origin is a cell off OctoMap's grid, exported; and in a version-1 .fot, whose
# nodes sat 0x2AAA cells off today's.
tool_test(Hostile.Cost.OffGridExportIsRefusedAtOnce COMMAND $<TARGET_FILE:fot_convert>
          "${PROJECT_SOURCE_DIR}/test/data/hostile/cube_off_grid.fot" "${h}/moved.bt" EXIT 2 ONE_LINE_ERROR
          MATCH "would need up to" ABSENT "${h}/moved.bt")
tool_test(Hostile.Cost.VersionOneCubeIsRefusedAtOnce COMMAND $<TARGET_FILE:fot_info>
          "${PROJECT_SOURCE_DIR}/test/data/hostile/cube_v1.fot" EXIT 2 ONE_LINE_ERROR MATCH "would need up to")
