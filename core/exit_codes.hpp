// The one exit-status convention of every sweepmap command and process (docs/reference/
// exit-codes.md). A script can tell from the status alone whose problem it is: the input's,
// the caller's, or the device's.
//
// Where a case could read two ways, the rule is:
//  - a file named on the command line that does not exist or cannot be read (a log, a
//    capture, a rig file) is a usage error (2): the caller named the wrong thing. The same
//    for every command (replay, dump, eval, calib, decode, import).
//  - a file that opens but holds the wrong thing (corrupt bytes, a log of another rig kind,
//    an empty log) is bad input (1), and so is a run that produced nothing usable.
//  - writing an output that fails (no space, a read-only folder) is an I/O failure (4);
//    an output path that cannot be right (a file where a folder is wanted, a non-empty
//    folder without --force) is a usage error (2).
//  - the command-line parser's own errors (a missing or unknown option, a value out of
//    range) are usage errors (2); --help and --version exit 0 (core/command_line.hpp).
#pragma once

namespace sweepmap {

enum ExitCode : int {
  kExitOk = 0,              // success
  kExitBadInput = 1,        // the input held a problem: corrupt data, a log of another rig kind,
                            // an empty log, no usable sweep (what was produced is kept)
  kExitUsage = 2,           // usage or config error: bad option, bad rig file, bad --out
  kExitDeviceIdentity = 3,  // the device answered but is not the model the rig file names
  kExitDeviceIo = 4,        // device or I/O failure: cannot open, read or write
};

}  // namespace sweepmap
