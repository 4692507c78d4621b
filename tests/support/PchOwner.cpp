// Compiles the test programs' precompiled header (tests/CMakeLists.txt: rastercheck_test_pch); the
// program itself does nothing.
int main() { return 0; }
