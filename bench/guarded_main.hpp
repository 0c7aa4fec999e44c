// The entry of every bench program: a bad argument or scene ends the program with the error's
// message and exit status 2, not with an uncaught exception's abort.
#pragma once

#include <cstdio>
#include <exception>

namespace bench {

template <class Body>
int guarded_main(const char* name, int argc, char** argv, Body body) {
  try {
    return body(argc, argv);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "%s: %s\n", name, e.what());
    return 2;
  }
}

}  // namespace bench
