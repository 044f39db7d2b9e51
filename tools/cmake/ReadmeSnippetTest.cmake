# ctest "docs: README's physical grasp is grasp_with_mass's code": the lines of
# tools/examples/grasp_with_mass/main.cpp between "// README begins" and "// README ends"
# (their common four-space indent removed) must appear in README.md as one ```cpp block, byte
# for byte, so the README's ten lines are code that builds and runs (the example's own test).
# Usage: cmake -DSOURCE_DIR=<hapto> -P ReadmeSnippetTest.cmake
file(READ ${SOURCE_DIR}/tools/examples/grasp_with_mass/main.cpp source)
string(FIND "${source}" "    // README begins\n" begin)
string(FIND "${source}" "    // README ends\n" end)
if(begin EQUAL -1 OR end EQUAL -1 OR end LESS begin)
  message(FATAL_ERROR "grasp_with_mass/main.cpp: no '// README begins' ... '// README ends' lines")
endif()
string(LENGTH "    // README begins\n" skip)
math(EXPR first "${begin} + ${skip}")
math(EXPR length "${end} - ${first}")
string(SUBSTRING "${source}" ${first} ${length} snippet)
# (CMake's ^ matches again at each new search start, so the indent goes line by line: "\n    ".)
string(REPLACE "\n    " "\n" snippet "\n${snippet}")
string(SUBSTRING "${snippet}" 1 -1 snippet)
file(READ ${SOURCE_DIR}/README.md readme)
string(FIND "${readme}" "```cpp\n${snippet}```\n" found)
if(found EQUAL -1)
  message(FATAL_ERROR "README.md does not show grasp_with_mass's lines between '// README begins' "
                      "and '// README ends' exactly in a ```cpp block; copy them (without their "
                      "four-space indent):\n${snippet}")
endif()
