// The holder of the test programs' precompiled header (tests/CMakeLists.txt, dg_test_pch): a
// program with no tests of its own, built so that the header is compiled once.
