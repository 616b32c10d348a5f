#!/bin/sh
# pcfile.sh TEMPLATE - print the pkg-config file TEMPLATE with each @KEY@
# replaced by the environment variable PC_KEY, taken literally (no sed or
# shell meaning: a prefix may hold spaces, quotes, '|' or '&'). The
# directories PC_PREFIX, PC_LIBDIR and PC_INCLUDEDIR get pkg-config's
# escapes (a backslash before each space, quote and backslash), so that
# `pkg-config --cflags` prints them as one shell word each.
set -eu
esc() { printf '%s' "$1" | sed 's/[\\ "'"'"']/\\&/g'; }
PC_PREFIX=$(esc "$PC_PREFIX")
PC_LIBDIR=$(esc "$PC_LIBDIR")
PC_INCLUDEDIR=$(esc "$PC_INCLUDEDIR")
export PC_PREFIX PC_LIBDIR PC_INCLUDEDIR
awk '{
  out = ""
  while (match($0, /@[A-Z_]+@/)) {
    key = "PC_" substr($0, RSTART + 1, RLENGTH - 2)
    if (!(key in ENVIRON)) { print "pcfile.sh: " key " is not set" > "/dev/stderr"; exit 1 }
    out = out substr($0, 1, RSTART - 1) ENVIRON[key]
    $0 = substr($0, RSTART + RLENGTH)
  }
  print out $0
}' "$1"
