# Fails unless the AVX kernel's object defines exactly one global symbol, its kKernel, and no weak
# (shared) one. Run by ctest (avx_kernel_shares_no_code) with -DNM= and -DOBJECTS= (a list).
list(FILTER OBJECTS INCLUDE REGEX "newton_lagrange_kernel_avx")
list(LENGTH OBJECTS count)
if(NOT count EQUAL 1)
  message(FATAL_ERROR "expected one AVX kernel object, found ${count}: ${OBJECTS}")
endif()
execute_process(COMMAND ${NM} -C --defined-only ${OBJECTS} OUTPUT_VARIABLE symbols
                RESULT_VARIABLE status)
if(NOT status EQUAL 0)
  message(FATAL_ERROR "${NM} failed on ${OBJECTS}")
endif()
string(REGEX MATCHALL "[^\n]* [A-Zuvw] [^\n]*" global "${symbols}")
if(NOT global MATCHES "^[0-9a-f]+ [DR] accelcal::internal::newton_kernel::avx::kKernel$")
  message(FATAL_ERROR "the AVX kernel object defines shared symbols besides kKernel:\n${global}")
endif()
message(STATUS "AVX kernel object: only kKernel is global")
