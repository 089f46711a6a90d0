package component

import (
	"errors"
	"fmt"
	"net"
	"os"
	"path/filepath"
	"strconv"
	"strings"
)

// listen opens the listening socket for an address given as "host:port"
// (port 0 picks a free one) or "unix:/path", and returns it with the
// address to tell others: the real port, an absolute socket path.
func listen(address string) (net.Listener, string, error) {
	if path, ok := unixPath(address); ok {
		return listenUnix(path)
	}
	host, _, err := net.SplitHostPort(address)
	if err != nil {
		return nil, "", fmt.Errorf("listen address %q is neither host:port nor unix:/path", address)
	}
	listener, err := net.Listen("tcp", address)
	if err != nil {
		return nil, "", err
	}
	if host == "" {
		// Listening on every interface; this machine reaches it as localhost.
		host = "localhost"
	}
	port := listener.Addr().(*net.TCPAddr).Port
	return listener, net.JoinHostPort(host, strconv.Itoa(port)), nil
}

// unixPath is the socket path of a "unix:path" or "unix:///path" address.
func unixPath(address string) (string, bool) {
	if rest, ok := strings.CutPrefix(address, "unix://"); ok {
		return rest, rest != ""
	}
	if rest, ok := strings.CutPrefix(address, "unix:"); ok {
		return rest, rest != ""
	}
	return "", false
}

func listenUnix(path string) (net.Listener, string, error) {
	absolute, err := filepath.Abs(path)
	if err != nil {
		return nil, "", err
	}
	if err := removeStaleSocket(absolute); err != nil {
		return nil, "", err
	}
	listener, err := net.Listen("unix", absolute)
	if err != nil {
		return nil, "", err
	}
	return listener, "unix:" + absolute, nil
}

// removeStaleSocket deletes a socket file that a process which ended
// without cleaning up left behind; one that still answers is in use.
func removeStaleSocket(path string) error {
	info, err := os.Lstat(path)
	if errors.Is(err, os.ErrNotExist) {
		return nil
	}
	if err != nil {
		return err
	}
	if info.Mode()&os.ModeSocket == 0 {
		return fmt.Errorf("%s exists and is not a socket", path)
	}
	if conn, err := net.Dial("unix", path); err == nil {
		conn.Close()
		return fmt.Errorf("%s is in use by another process", path)
	}
	return os.Remove(path)
}
