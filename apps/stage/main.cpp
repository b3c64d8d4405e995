// A single stage as its own program: prt-NAME ARGS behaves exactly as prt NAME ARGS.
#include "cli.h"

int main(int argc, char** argv) { return prt::cli::runDriver(argc, argv, PRT_STAGE); }
