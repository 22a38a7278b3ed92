# nbv_embed_files(<target> HEADER <header> NAMESPACE <ns> FILES <constant> <file> ...): each
# file's bytes, read at build time, as a `const std::string_view <constant>` in namespace <ns>,
# compiled into <target>. <header> (as the target includes it) declares the constants. A file
# that changes is embedded again at the next build. Run as a script (cmake -P), this file writes
# the source.

if(CMAKE_SCRIPT_MODE_FILE)
  string(REPLACE "|" ";" entries "${ENTRIES}")
  set(text "// Generated at build time by cmake/NbvEmbed.cmake: edit the files it embeds instead.\n")
  string(APPEND text "#include \"${HEADER}\"\n\nnamespace ${NAMESPACE} {\n")
  list(LENGTH entries count)
  math(EXPR last "${count} - 1")
  foreach(i RANGE 0 ${last} 2)
    math(EXPR j "${i} + 1")
    list(GET entries ${i} constant)
    list(GET entries ${j} file)
    file(READ "${file}" content)
    string(FIND "${content}" ")nbv_embed\"" clash)
    if(NOT clash EQUAL -1)
      message(FATAL_ERROR "${file} holds the text ')nbv_embed\"', which ends the raw string it is embedded in")
    endif()
    string(APPEND text "\nconst std::string_view ${constant} = R\"nbv_embed(${content})nbv_embed\";\n")
  endforeach()
  string(APPEND text "\n}  // namespace ${NAMESPACE}\n")
  file(WRITE "${OUTPUT}.tmp" "${text}")
  file(RENAME "${OUTPUT}.tmp" "${OUTPUT}")
  return()
endif()

set(NBV_EMBED_SCRIPT ${CMAKE_CURRENT_LIST_FILE})

function(nbv_embed_files target)
  cmake_parse_arguments(PARSE_ARGV 1 arg "" "HEADER;NAMESPACE" "FILES")
  set(entries "")
  set(files "")
  list(LENGTH arg_FILES count)
  math(EXPR last "${count} - 1")
  foreach(i RANGE 0 ${last} 2)
    math(EXPR j "${i} + 1")
    list(GET arg_FILES ${i} constant)
    list(GET arg_FILES ${j} file)
    get_filename_component(file ${file} ABSOLUTE BASE_DIR ${CMAKE_CURRENT_SOURCE_DIR})
    list(APPEND files ${file})
    string(APPEND entries "${constant}|${file}|")
  endforeach()
  string(REGEX REPLACE "\\|$" "" entries "${entries}")
  string(MAKE_C_IDENTIFIER "${arg_HEADER}" stem)
  set(output ${CMAKE_CURRENT_BINARY_DIR}/embedded_${stem}.cpp)
  add_custom_command(
    OUTPUT ${output}
    COMMAND ${CMAKE_COMMAND} -DOUTPUT=${output} -DHEADER=${arg_HEADER} -DNAMESPACE=${arg_NAMESPACE}
            -DENTRIES=${entries} -P ${NBV_EMBED_SCRIPT}
    DEPENDS ${files} ${NBV_EMBED_SCRIPT}
    COMMENT "Embedding ${arg_HEADER}'s files"
    VERBATIM)
  target_sources(${target} PRIVATE ${output})
endfunction()
