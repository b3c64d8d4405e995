#include "cli.h"

int main(int argc, char** argv) { return prt::cli::runDriver(argc, argv); }
