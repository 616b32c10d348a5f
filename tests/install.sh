#!/bin/sh
# install.sh SCENARIO - `make install` as a packager and a user run it, from
# tests/ (check_install.c), each scenario in its own temporary directory:
#
#   destdir  DESTDIR=TMP/stage PREFIX=/opt/hbvm: every file in place (the
#            runtimes and their .pc files, the man page, the docs and
#            examples under share/doc/hbvmgen, which the man page names);
#            libhbvmrt.so.VERSION carries the soname libhbvmrt.so.MAJOR and
#            both links point to it; a pendulum driver built with pkg-config
#            alone (PKG_CONFIG_SYSROOT_DIR=TMP/stage) against the shared
#            runtime, the static one and hbvmrt_omp, and with MPI=1 against
#            hbvmrt_mpi through mpicc, runs and prints the model's CSV header;
#   strip    the installed generator has no symbol table (STRIP= keeps it),
#            and every shared library it needs is named in the README;
#   quoted   a PREFIX with a space, then one with quotes, '&' and '|' too:
#            nothing is created in the source tree, every file lands under
#            PREFIX, pkg-config prints each directory as one shell word, a
#            driver built from its flags runs, and make uninstall leaves no
#            file behind.
#
# Under the sanitizers (HBVM_SANITIZED) make installs the instrumented
# generator and runtimes, so the programs are built with -fsanitize too.
# Exit status 0 pass, 1 fail (a message on stderr says what).
# shellcheck disable=SC2089,SC2090 # the quotes in the prefix are its own
set -u
scenario=$1
top=$(cd .. && pwd)
san=${HBVM_SANITIZED:-}
SAN_CFLAGS=""
[ -n "$san" ] && SAN_CFLAGS="-fsanitize=address,undefined -fno-omit-frame-pointer"
HEADER="t,x,y,p_x,p_y,lambda_1,H,g_1,hc_1"
tmp=$(mktemp -d /tmp/hbvm-install-XXXXXX) || exit 1
trap 'rm -rf "$tmp"' EXIT INT TERM

fail() {
  echo "install.sh $scenario: $*" >&2
  exit 1
}

# make install (or uninstall, $1) from the top of the tree with the
# variables $2..., as this run was built.
run_make() {
  target=$1
  shift
  (cd "$top" && env -u MAKEFLAGS -u MAKELEVEL -u MFLAGS make -s "$target" SANITIZE="$san" "$@" >"$tmp/make.log" 2>&1) ||
    { cat "$tmp/make.log" >&2; fail "make $target $* failed"; }
}

# The pendulum generated with --main into $tmp/out by the generator $1.
generate() {
  mkdir -p "$tmp/out"
  "$1" --main -o "$tmp/out" "$top/models/pendulum.ham" || fail "$1 cannot generate the pendulum"
}

# Build the pendulum driver $1 with compiler $2 and the flags that follow
# (pkg-config's output, parsed by the shell as in a Makefile recipe's
# `$(shell pkg-config ...)`: its backslashes escape), run it (with LD_LIBRARY_PATH=$3 unless $3 is empty)
# and check its CSV header.
build_and_run() {
  prog=$1 cc=$2 libdir=$3
  shift 3
  eval "$cc -O2 -std=c99 $SAN_CFLAGS -I\"\$tmp/out\" \"\$tmp/out/pendulum.c\" \"\$tmp/out/pendulum_main.c\" $* -o \"\$prog\"" ||
    fail "building $prog failed: $cc ... $*"
  if [ -n "$libdir" ]; then
    line=$(LD_LIBRARY_PATH=$libdir "$prog" -h 0.1 -N 2 --quiet --csv - 2>/dev/null | head -n 1)
  else
    line=$("$prog" -h 0.1 -N 2 --quiet --csv - 2>/dev/null | head -n 1)
  fi
  [ "$line" = "$HEADER" ] || fail "$prog printed '$line', want '$HEADER'"
}

# The dynamic section's NEEDED entries of ELF file $1, one a line.
needed() {
  readelf -d "$1" | sed -n 's/.*(NEEDED).*\[\(.*\)\]/\1/p'
}

version=$(sed -n 's/^#define HBVMGEN_VERSION "\(.*\)"/\1/p' "$top/gen/hbvmgen.h")
major=${version%%.*}

case "$scenario" in
destdir)
  stage=$tmp/stage root=$tmp/stage/opt/hbvm
  mpi=""
  command -v mpicc >/dev/null 2>&1 && mpi=1
  run_make install DESTDIR="$stage" PREFIX=/opt/hbvm MPI="$mpi"
  for f in bin/hbvmgen include/hbvmrt.h share/man/man1/hbvmgen.1 \
    lib/libhbvmrt.a lib/libhbvmrt_omp.a lib/libhbvmrt.so."$version" \
    lib/pkgconfig/hbvmrt.pc lib/pkgconfig/hbvmrt_omp.pc \
    share/doc/hbvmgen/README.md share/doc/hbvmgen/examples/embed.c share/doc/hbvmgen/models/pendulum.ham \
    ${mpi:+lib/libhbvmrt_mpi.a lib/pkgconfig/hbvmrt_mpi.pc}; do
    [ -f "$root/$f" ] || fail "make install did not install $f"
  done
  for f in "$top"/docs/*.md "$top"/docs/examples/* "$top"/models/*.ham; do
    rel=${f#"$top"/}
    rel=${rel#docs/}
    [ -f "$root/share/doc/hbvmgen/$rel" ] || fail "make install did not install $rel under share/doc/hbvmgen"
  done
  grep -q 'share/doc/hbvmgen' "$top/docs/hbvmgen.1" || fail "the man page does not name share/doc/hbvmgen"
  # the shared runtime: soname, links, a driver that needs it
  so=$root/lib/libhbvmrt.so.$version
  readelf -d "$so" | grep -q "(SONAME).*\[libhbvmrt.so.$major\]" || fail "$so has no soname libhbvmrt.so.$major"
  [ "$(readlink "$root/lib/libhbvmrt.so.$major")" = "libhbvmrt.so.$version" ] || fail "libhbvmrt.so.$major is not a link to libhbvmrt.so.$version"
  [ "$(readlink "$root/lib/libhbvmrt.so")" = "libhbvmrt.so.$major" ] || fail "libhbvmrt.so is not a link to libhbvmrt.so.$major"
  grep -qx 'prefix=/opt/hbvm' "$root/lib/pkgconfig/hbvmrt.pc" || fail "hbvmrt.pc does not name the prefix /opt/hbvm"
  PKG_CONFIG_PATH=$root/lib/pkgconfig PKG_CONFIG_SYSROOT_DIR=$stage
  export PKG_CONFIG_PATH PKG_CONFIG_SYSROOT_DIR
  generate "$root/bin/hbvmgen"
  build_and_run "$tmp/shared" cc "$root/lib" "$(pkg-config --cflags --libs hbvmrt)"
  needed "$tmp/shared" | grep -qx "libhbvmrt.so.$major" || fail "the driver linked by pkg-config does not need libhbvmrt.so.$major"
  # the static runtime, from the same flags: -l:libhbvmrt.a
  build_and_run "$tmp/static" cc "" "$(pkg-config --cflags --libs-only-L hbvmrt) -l:libhbvmrt.a -lm"
  needed "$tmp/static" | grep -q libhbvmrt && fail "the driver linked with libhbvmrt.a still needs libhbvmrt.so"
  build_and_run "$tmp/omp" cc "" "$(pkg-config --cflags --libs hbvmrt_omp)"
  needed "$tmp/omp" | grep -q libgomp || fail "the driver linked by pkg-config hbvmrt_omp does not need libgomp"
  if [ -n "$mpi" ]; then
    build_and_run "$tmp/mpi" mpicc "" "$(pkg-config --cflags --libs hbvmrt_mpi)"
  fi
  ;;
strip)
  run_make install PREFIX="$tmp/stripped"
  run_make install PREFIX="$tmp/kept" STRIP=
  readelf -S "$tmp/stripped/bin/hbvmgen" | grep -q '\.symtab' && fail "the installed generator is not stripped"
  readelf -S "$tmp/kept/bin/hbvmgen" | grep -q '\.symtab' || fail "STRIP= stripped the generator all the same"
  "$tmp/stripped/bin/hbvmgen" --help >/dev/null || fail "the stripped generator does not run"
  if [ -z "$san" ]; then
    for lib in $(needed "$tmp/stripped/bin/hbvmgen"); do
      grep -q "${lib%%.so*}" "$top/README.md" || fail "the generator needs $lib, which README.md does not name"
    done
  fi
  ;;
quoted)
  # the word after a space is where the old install -d put directories
  word="hbvm-stray-$$"
  for prefix in "$tmp/a space $word" "$tmp/quotes's \"q\" & | $word"; do
    run_make install PREFIX="$prefix"
    [ -e "$top/$word" ] && { rm -rf "${top:?}/$word"; fail "make install created $word in the source tree"; }
    for f in bin/hbvmgen lib/libhbvmrt.a lib/libhbvmrt.so include/hbvmrt.h lib/pkgconfig/hbvmrt.pc \
      share/man/man1/hbvmgen.1 share/doc/hbvmgen/api.md; do
      [ -f "$prefix/$f" ] || fail "make install did not install '$prefix/$f'"
    done
    PKG_CONFIG_PATH=$prefix/lib/pkgconfig
    export PKG_CONFIG_PATH
    eval "set -- $(pkg-config --cflags hbvmrt)"
    [ "$1" = "-I$prefix/include" ] || fail "pkg-config --cflags hbvmrt gives '$1', want '-I$prefix/include'"
    rm -rf "$tmp/out"
    generate "$prefix/bin/hbvmgen"
    build_and_run "$tmp/driver" cc "$prefix/lib" "$(pkg-config --cflags --libs hbvmrt)"
    run_make uninstall PREFIX="$prefix"
    left=$(find "$prefix" -type f | head -n 3)
    [ -z "$left" ] || fail "make uninstall left $left"
  done
  ;;
*)
  fail "unknown scenario (destdir, strip, quoted)"
  ;;
esac
exit 0
