// The `ricochet` program: the command line is harness/cli/cli.hpp.
#include <iostream>
#include <string>
#include <vector>

#include "harness/cli/cli.hpp"

int main(int argc, char** argv) {
  return ricochet::ricochet_main(std::vector<std::string>(argv + 1, argv + argc), std::cout, std::cerr);
}
