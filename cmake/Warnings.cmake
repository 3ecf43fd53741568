# Warnings and sanitizers applied to every target of ours (not to the Debian libraries we link).
add_library(ballbar_warnings INTERFACE)
target_compile_options(ballbar_warnings INTERFACE
  -Wall -Wextra -Wpedantic -Wshadow -Wconversion -Wno-sign-conversion -Wnon-virtual-dtor
  -Wold-style-cast -Woverloaded-virtual -Wformat=2
  $<$<BOOL:${BALLBAR_WERROR}>:-Werror>)

if(BALLBAR_SANITIZE)
  add_compile_options(-fsanitize=address,undefined -fno-omit-frame-pointer -fno-sanitize-recover=undefined)
  # GCC's -Wmaybe-uninitialized reports false positives in instrumented code (seen in libstdc++'s
  # <regex>/std::function at -O1); the default build keeps it as an error.
  if(CMAKE_CXX_COMPILER_ID STREQUAL "GNU")
    target_compile_options(ballbar_warnings INTERFACE -Wno-maybe-uninitialized)
  endif()
  add_link_options(-fsanitize=address,undefined)
endif()

# libFuzzer targets (fuzz/, the `fuzz` preset): every library of ours, the CLI's objects and the fuzz
# targets get the fuzzer's coverage instrumentation (BALLBAR_COVERAGE_FLAGS) and the sanitizers, so the
# targets see the edges of the parsers they call. The targets themselves add -fsanitize=fuzzer at link
# time (libFuzzer's main). The tests and benchmarks are not instrumented for coverage: nothing fuzzes
# their own code, and it made the `asan` tree's tests 15 % slower to compile.
# With BALLBAR_SANITIZE too (the `asan` preset), the sanitizers are already on: only the coverage is added.
set(BALLBAR_COVERAGE_FLAGS "")
if(BALLBAR_FUZZ)
  set(BALLBAR_COVERAGE_FLAGS -fsanitize=fuzzer-no-link)
  if(NOT BALLBAR_SANITIZE)
    add_compile_options(-fsanitize=address,undefined -fno-sanitize-recover=undefined -fno-omit-frame-pointer)
    add_link_options(-fsanitize=address,undefined)
  endif()
endif()

# Debian's hardening (what dpkg-buildflags gives packages): fortified libc calls and a read-only,
# bound-at-start relocation table. Not with the sanitizers, which replace those calls themselves.
if(NOT BALLBAR_SANITIZE AND NOT BALLBAR_FUZZ)
  target_compile_definitions(ballbar_warnings INTERFACE $<$<NOT:$<CONFIG:Debug>>:_FORTIFY_SOURCE=2>)
  add_link_options(LINKER:-z,relro LINKER:-z,now)
endif()

# ballbar_module(NAME ...) : a static library of ours with the usual settings.
function(ballbar_module name)
  add_library(${name} STATIC ${ARGN})
  add_library(ballbar::${name} ALIAS ${name})
  target_include_directories(${name} PUBLIC ${CMAKE_CURRENT_SOURCE_DIR}/include)
  target_link_libraries(${name} PRIVATE ballbar_warnings)
  set_target_properties(${name} PROPERTIES POSITION_INDEPENDENT_CODE ON)
  # Position-independent, but linked statically into our executables: nobody interposes our symbols,
  # so let the compiler inline and specialise calls within a file as it would without -fPIC (the
  # compensation and Jacobian hot paths depend on it).
  target_compile_options(${name} PRIVATE -fno-semantic-interposition ${BALLBAR_COVERAGE_FLAGS})
  # Unity batches of four, as the CLI's and the tests' (CMakeLists.txt, BALLBAR_UNITY_BUILD): Eigen,
  # nlohmann-json and fmt generate their inline code once a batch. GCC's subobject-linkage warning takes a
  # type of one file's anonymous namespace, used by a class of that file, for one shared between
  # translation units; in a unity batch it is neither.
  set_target_properties(${name} PROPERTIES UNITY_BUILD ${BALLBAR_UNITY_BUILD} UNITY_BUILD_BATCH_SIZE 4)
  target_compile_options(${name} PRIVATE $<$<CXX_COMPILER_ID:GNU>:-Wno-subobject-linkage>)
endfunction()
