#pragma once
// The command lines of sarmap-procman (the sheriff) and sarmap-procman-deputy: options, key,
// LCM, the event loop; --help explains each. They return the exit status and throw
// common::ArgError on a bad command line (common::RunMain reports it).

namespace sarmap {
namespace procman {

int RunSheriff(int argc, char** argv);
int RunDeputy(int argc, char** argv);

}  // namespace procman
}  // namespace sarmap
