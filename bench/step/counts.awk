# counts.awk - the instructions executed by solver P's functions in a
# callgrind file written with --dump-instr=yes --dump-line=no: one line
# "function address count" (address in hex) per instruction of a function
# whose name starts with P_ (set with -v P=NAME). bench/step/run.sh picks the
# step's iteration from the counts.
function hex(s,   i, v) {
  v = 0
  for (i = 1; i <= length(s); i++) v = v * 16 + index("0123456789abcdef", substr(s, i, 1)) - 1
  return v
}
# "(12) name" at a name's first use, "(12)" after it: the name either way
function name(s,   id) {
  if (match(s, /^\([0-9]+\)/)) {
    id = substr(s, RSTART, RLENGTH)
    s = substr(s, RLENGTH + 2)
    if (s != "") names[id] = s
    else s = names[id]
  }
  return s
}
/^fn=/ { fn = name(substr($0, 4)); next }
/^cfn=/ { name(substr($0, 5)); next }
/^c(ob|fi|fe|fl)=/ { next }
/^calls=/ { call = 1; next }
/^(0x[0-9a-f]+|[+-][0-9]+|\*) / {
  p = $1
  if (p ~ /^0x/) pos = hex(substr(p, 3))
  else if (p ~ /^\+/) pos += substr(p, 2) + 0
  else if (p ~ /^-/) pos -= substr(p, 2) + 0
  if (call) { call = 0; next } # a call's inclusive cost, at its call site
  if (index(fn, P "_") == 1) count[fn " " pos] += $2
}
END {
  for (k in count) {
    split(k, a, " ")
    printf "%s %x %d\n", a[1], a[2], count[k]
  }
}
