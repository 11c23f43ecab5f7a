# Helper functions shared by every module's CMakeLists.

# Warnings as an INTERFACE target; -Werror only when TETRAPROBE_WERROR is on (CI).
add_library(tetraprobe_warnings INTERFACE)
target_compile_options(tetraprobe_warnings INTERFACE -Wall -Wextra -Wpedantic -Wno-missing-field-initializers
  $<$<BOOL:${TETRAPROBE_WERROR}>:-Werror>
  # GCC 12's -Wrestrict misfires inside std::string concatenation (GCC bug 105651).
  $<$<CXX_COMPILER_ID:GNU>:-Wno-restrict>)
# Strict IEEE floating point everywhere: CGAL's predicates and the bit-identical bake depend on it.
target_compile_options(tetraprobe_warnings INTERFACE -fno-fast-math -ffp-contract=off)

# Sanitizers apply to every target of the build (libraries, tests, tools), so they are directory-wide options
# rather than an INTERFACE target: a static library compiled without them would hide its bugs.
# TETRAPROBE_SANITIZE: ASan + UBSan (any compiler; float-to-int overflow included, which GCC leaves out of
# -fsanitize=undefined). TETRAPROBE_FUZZ: the same plus libFuzzer's coverage (clang only).
macro(tetraprobe_enable_sanitizers)
  set(_tp_san -fsanitize=address,undefined,float-cast-overflow -fno-sanitize-recover=undefined,float-cast-overflow
      -fno-omit-frame-pointer)
  if(TETRAPROBE_FUZZ)
    if(NOT CMAKE_CXX_COMPILER_ID MATCHES "Clang")
      message(FATAL_ERROR "TETRAPROBE_FUZZ needs clang (libFuzzer): configure with -DCMAKE_CXX_COMPILER=clang++")
    endif()
    add_compile_options(${_tp_san} -fsanitize=fuzzer-no-link)
    add_link_options(-fsanitize=address,undefined)
  elseif(TETRAPROBE_SANITIZE)
    add_compile_options(${_tp_san})
    add_link_options(-fsanitize=address,undefined)
  endif()
endmacro()

# tetraprobe_add_module(NAME SOURCES ... [PUBLIC_LIBS ...] [PRIVATE_LIBS ...])
# Builds tetraprobe_<NAME> with public headers under <dir>/include, aliased tetraprobe::<NAME>.
function(tetraprobe_add_module name)
  cmake_parse_arguments(ARG "" "" "SOURCES;PUBLIC_LIBS;PRIVATE_LIBS" ${ARGN})
  add_library(tetraprobe_${name} STATIC ${ARG_SOURCES})
  add_library(tetraprobe::${name} ALIAS tetraprobe_${name})
  target_include_directories(tetraprobe_${name} PUBLIC
    $<BUILD_INTERFACE:${CMAKE_CURRENT_SOURCE_DIR}/include> $<INSTALL_INTERFACE:include>)
  target_link_libraries(tetraprobe_${name} PUBLIC ${ARG_PUBLIC_LIBS} PRIVATE ${ARG_PRIVATE_LIBS} tetraprobe_warnings)
  set_target_properties(tetraprobe_${name} PROPERTIES POSITION_INDEPENDENT_CODE ON)
endfunction()

# tetraprobe_add_test(NAME SOURCES ... LIBS ...): one gtest executable, tests discovered for ctest. Every test
# sees tests/common (missing_capability.h: skip, or fail under TETRAPROBE_REQUIRE_ALL=1).
function(tetraprobe_add_test name)
  cmake_parse_arguments(ARG "" "" "SOURCES;LIBS" ${ARGN})
  add_executable(${name} ${ARG_SOURCES})
  target_link_libraries(${name} PRIVATE ${ARG_LIBS} GTest::gtest GTest::gtest_main tetraprobe_warnings)
  target_include_directories(${name} PRIVATE ${PROJECT_SOURCE_DIR}/tests/common)
  target_compile_definitions(${name} PRIVATE
    TETRAPROBE_SOURCE_DIR="${PROJECT_SOURCE_DIR}"
    TETRAPROBE_SHARED_SCENES="${PROJECT_SOURCE_DIR}/../shared/scenes")
  include(GoogleTest)
  gtest_discover_tests(${name} DISCOVERY_TIMEOUT 60 PROPERTIES TIMEOUT 900)
endfunction()

# The runtime is shipped inside engines: fail the configure if it ever links a build-side library.
function(tetraprobe_check_licence_boundary target)
  get_target_property(libs ${target} LINK_LIBRARIES)
  foreach(lib IN LISTS libs)
    if(lib MATCHES "CGAL|TetGen|tet$|embree|TBB|gmp|mpfr|CAIRO|cairo")
      message(FATAL_ERROR "Licence boundary: ${target} links build-side library '${lib}'")
    endif()
  endforeach()
endfunction()

# tetraprobe_embed_spirv(TARGET OUT_DIR SHADERS ... [INCLUDE_DIRS ...] [DEPENDS ...]): compiles each GLSL file to
# SPIR-V at build time with glslangValidator (--vn), giving OUT_DIR/<file>.h with an array kSpirv_<file_ext>
# (gbuffer.vert -> kSpirv_gbuffer_vert). No .spv is ever committed. TARGET is an INTERFACE library exposing OUT_DIR.
function(tetraprobe_embed_spirv target out_dir)
  cmake_parse_arguments(ARG "" "" "SHADERS;INCLUDE_DIRS;DEPENDS" ${ARGN})
  set(headers)
  set(incs)
  foreach(d IN LISTS ARG_INCLUDE_DIRS)
    list(APPEND incs -I${d})
  endforeach()
  foreach(src IN LISTS ARG_SHADERS)
    get_filename_component(fname ${src} NAME)
    string(MAKE_C_IDENTIFIER ${fname} ident)
    set(out ${out_dir}/${fname}.h)
    add_custom_command(OUTPUT ${out}
      COMMAND ${CMAKE_COMMAND} -E make_directory ${out_dir}
      COMMAND ${GLSLANG_VALIDATOR} --quiet -V --target-env vulkan1.1 ${incs} --vn kSpirv_${ident} -o ${out} ${src}
      DEPENDS ${src} ${ARG_DEPENDS}
      COMMENT "glslang ${fname}" VERBATIM)
    list(APPEND headers ${out})
  endforeach()
  add_custom_target(${target}_gen DEPENDS ${headers})
  add_library(${target} INTERFACE)
  target_include_directories(${target} INTERFACE ${out_dir})
  add_dependencies(${target} ${target}_gen)
endfunction()
