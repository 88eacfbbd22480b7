# Every "CONVENTIONS n" citation in the source tree (code, tests, docs) names a section docs/CONVENTIONS.md
# has (a heading "## n. Title"; a range "CONVENTIONS 3-6" needs both ends), and no "SPEC n" citation is left:
# there is no SPEC in the repository, its conventions are docs/CONVENTIONS.md.
#   cmake -DSOURCE_DIR=<repository> -P check_conventions_citations.cmake
#   cmake -DSELF_TEST=ON -DWORK_DIR=<scratch> -P check_conventions_citations.cmake
# The second runs the check on a made-up tree with known faults and fails unless it reports exactly them.
cmake_minimum_required(VERSION 3.16)

# The folders and top-level files that hold citations (never a build tree).
set(scanned_folders libocc_improve pcl_tools python tests docs samples scripts cmake)
set(scanned_extensions cpp hpp h py pyi md txt cmake)

# The problems of the tree at `root`, one "<file>: <problem>" per entry, into `problems_var`; how many
# citations were read, into `count_var`.
function(conventions_problems root problems_var count_var)
  file(STRINGS "${root}/docs/CONVENTIONS.md" headings REGEX "^## [0-9]+[a-z]?\\. ")
  set(sections)
  foreach(heading IN LISTS headings)
    string(REGEX REPLACE "^## ([0-9]+[a-z]?)\\. .*" "\\1" section "${heading}")
    list(APPEND sections "${section}")
  endforeach()
  set(patterns "${root}/*.md" "${root}/CMakeLists.txt")
  foreach(folder IN LISTS scanned_folders)
    foreach(extension IN LISTS scanned_extensions)
      list(APPEND patterns "${root}/${folder}/*.${extension}")
    endforeach()
  endforeach()
  file(GLOB_RECURSE files LIST_DIRECTORIES false RELATIVE "${root}" ${patterns})
  set(problems)
  set(count 0)
  foreach(file IN LISTS files)
    file(STRINGS "${root}/${file}" lines REGEX "(CONVENTIONS|SPEC) [0-9]")
    foreach(line IN LISTS lines)
      string(REGEX MATCHALL "(CONVENTIONS|SPEC) [0-9]+[a-z]?(-[0-9]+[a-z]?)?" citations "${line}")
      foreach(citation IN LISTS citations)
        math(EXPR count "${count} + 1")
        if(citation MATCHES "^SPEC")
          list(APPEND problems "${file}: cites ${citation}: the conventions are docs/CONVENTIONS.md, cited as CONVENTIONS n")
          continue()
        endif()
        string(REGEX REPLACE "^CONVENTIONS " "" range "${citation}")
        string(REPLACE "-" ";" ends "${range}")
        foreach(end IN LISTS ends)
          if(NOT end IN_LIST sections)
            list(APPEND problems "${file}: cites ${citation}, but docs/CONVENTIONS.md has no section ${end}")
          endif()
        endforeach()
      endforeach()
    endforeach()
  endforeach()
  set(${problems_var} "${problems}" PARENT_SCOPE)
  set(${count_var} "${count}" PARENT_SCOPE)
endfunction()

if(SELF_TEST)
  # The citations are written in pieces so that this file itself cites nothing.
  set(c "CONVENT")
  set(s "SP")
  file(REMOVE_RECURSE "${WORK_DIR}")
  file(WRITE "${WORK_DIR}/docs/CONVENTIONS.md" "# Conventions\n## 1. One\ntext\n## 2b. Two b\n")
  file(WRITE "${WORK_DIR}/libocc_improve/a.hpp" "// ${c}IONS 2b, ${c}IONS 1-2b and ${c}IONS 3; ${s}EC 1\n")
  file(WRITE "${WORK_DIR}/tests/b.py" "# ${c}IONS 2 is not 2b\n")
  file(WRITE "${WORK_DIR}/build/c.cpp" "// ${c}IONS 9 in a build tree is not read\n")
  conventions_problems("${WORK_DIR}" problems count)
  set(expected
      "libocc_improve/a.hpp: cites ${c}IONS 3, but docs/CONVENTIONS.md has no section 3"
      "libocc_improve/a.hpp: cites ${s}EC 1: the conventions are docs/CONVENTIONS.md, cited as CONVENTIONS n"
      "tests/b.py: cites ${c}IONS 2, but docs/CONVENTIONS.md has no section 2")
  list(SORT problems)
  list(SORT expected)
  if(NOT problems STREQUAL expected OR NOT count EQUAL 5)
    string(REPLACE ";" "\n  " shown "${problems}")
    message(FATAL_ERROR "the check found ${count} citations and these problems:\n  ${shown}")
  endif()
  message(STATUS "the check reports a missing section, a missing end of a range and an old citation")
  return()
endif()

conventions_problems("${SOURCE_DIR}" problems count)
if(problems)
  string(REPLACE ";" "\n  " shown "${problems}")
  message(FATAL_ERROR "citations of sections docs/CONVENTIONS.md does not have:\n  ${shown}")
endif()
if(count LESS 40)  # the code cites the conventions ~70 times: far fewer means the scan missed the tree
  message(FATAL_ERROR "only ${count} citations found under ${SOURCE_DIR}: is the scan looking at the right tree?")
endif()
message(STATUS "${count} citations, each of a section docs/CONVENTIONS.md has")
