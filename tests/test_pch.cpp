// The translation unit that builds the tests' precompiled header (tests/CMakeLists.txt,
// adaptseg_test_pch); the header list is there. Nothing else.
