# Finds a Go toolchain at least as new as go.mod asks for, or fetches one.
# Sourced by build.sh and test.sh; sets GO to the go binary and exports
# GOTOOLCHAIN=local so that go never switches toolchains behind our back.
#
# Where it looks, in order: $GO when set (only there), else go on PATH,
# /usr/local/go/bin/go, and a toolchain fetched before. Failing those, it
# downloads the module golang.org/toolchain from the Go module proxy (what
# go itself does for GOTOOLCHAIN) and unpacks it into $TOOLS.

GO_FETCH_VERSION=1.26.11
# sha256 of the proxy's zip, per architecture we can check.
declare -A GO_FETCH_SHA256=(
  [amd64]=e1edb778de0aa08c8e827f5a873b35a46afe680fb241482c531725b2355e470d
)

# The go directive of go.mod, e.g. 1.24.0.
go_required_version() {
  awk '$1 == "go" { print $2; exit }' "$MODULE_DIR/go.mod"
}

# Whether $1 runs and is at least version $2.
go_is_new_enough() {
  local have
  have=$("$1" env GOVERSION 2>/dev/null) || return 1
  have=${have#go}
  [ "$(printf '%s\n%s\n' "$2" "$have" | sort -V | head -n1)" = "$2" ]
}

go_fetch_arch() {
  case $(uname -m) in
    x86_64 | amd64) echo amd64 ;;
    aarch64 | arm64) echo arm64 ;;
    *) uname -m ;;
  esac
}

go_download() { # url file
  if command -v curl >/dev/null; then
    curl -fsSL --retry 3 -o "$2" "$1"
  elif command -v wget >/dev/null; then
    wget -q -O "$2" "$1"
  else
    echo "toolchain.sh: neither curl nor wget is installed" >&2
    return 1
  fi
}

go_unzip() { # zip dir
  if command -v unzip >/dev/null; then
    unzip -q "$1" -d "$2"
  elif command -v python3 >/dev/null; then
    python3 -m zipfile -e "$1" "$2"
  else
    echo "toolchain.sh: neither unzip nor python3 is installed" >&2
    return 1
  fi
}

# Fetches Go $GO_FETCH_VERSION into $TOOLS/go$GO_FETCH_VERSION.linux-ARCH
# unless it is already there; sets GO.
go_fetch() {
  local arch name dir proxy url tmp unpacked
  arch=$(go_fetch_arch)
  name=go$GO_FETCH_VERSION.linux-$arch
  dir=$TOOLS/$name
  if [ -x "$dir/bin/go" ]; then
    GO=$dir/bin/go
    return 0
  fi
  local sha=${GO_FETCH_SHA256[$arch]:-}
  if [ -z "$sha" ]; then
    echo "toolchain.sh: no Go >= $(go_required_version) found and none to fetch for $arch; install one" >&2
    return 1
  fi
  proxy=${GOPROXY:-https://proxy.golang.org}
  proxy=${proxy%%[,|]*}
  case $proxy in http://* | https://*) ;; *) proxy=https://proxy.golang.org ;; esac
  url=$proxy/golang.org/toolchain/@v/v0.0.1-$name.zip
  echo "fetching Go $GO_FETCH_VERSION from $url" >&2
  mkdir -p "$TOOLS"
  tmp=$(mktemp -d "$TOOLS/.fetch.XXXXXX")
  go_download "$url" "$tmp/go.zip" &&
    echo "$sha  $tmp/go.zip" | sha256sum -c --quiet - &&
    go_unzip "$tmp/go.zip" "$tmp/unpacked" || {
    rm -rf "$tmp"
    echo "toolchain.sh: could not fetch Go from $url" >&2
    return 1
  }
  unpacked=$tmp/unpacked/golang.org/toolchain@v0.0.1-$name
  # Module zips carry no file modes: the tools must be made executable.
  chmod +x "$unpacked"/bin/* "$unpacked"/pkg/tool/*/*
  mv "$unpacked" "$dir"
  rm -rf "$tmp"
  GO=$dir/bin/go
}

# Sets GO; returns non-zero when no usable toolchain can be had.
find_go() {
  local required candidate
  required=$(go_required_version)
  mkdir -p "$TOOLS"
  # .tools holds downloads only; keep it out of version control.
  [ -f "$TOOLS/.gitignore" ] || echo '*' >"$TOOLS/.gitignore"
  export GOTOOLCHAIN=local
  local candidates=()
  if [ -n "${GO:-}" ]; then
    candidates=("$GO")
  else
    candidates=("$(command -v go || true)" /usr/local/go/bin/go)
  fi
  candidates+=("$TOOLS/go$GO_FETCH_VERSION.linux-$(go_fetch_arch)/bin/go")
  for candidate in "${candidates[@]}"; do
    if [ -n "$candidate" ] && go_is_new_enough "$candidate" "$required"; then
      GO=$candidate
      return 0
    fi
  done
  if [ -n "${GO:-}" ]; then
    echo "GO=$GO is not a Go >= $required; fetching one" >&2
  fi
  go_fetch && go_is_new_enough "$GO" "$required"
}
