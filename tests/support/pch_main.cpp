// The target that owns the tests' precompiled header (tests/CMakeLists.txt); it runs no test.
int main() {
  return 0;
}
