// Placeholder until the services layer lands; replaced by the real CLI.
#include <cstdio>
int main() {
  std::puts("combabc " COMBABC_VERSION);
  return 0;
}
