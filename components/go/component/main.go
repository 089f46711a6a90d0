package component

import (
	"flag"
	"fmt"
	"os"
	"path/filepath"
	"time"
)

// Main is the whole main function of a component command: it reads
//
//	--listen ADDR [--register YARFD_ADDR] [--lease SECONDS]
//
// from the command line, serves the classes until SIGINT or SIGTERM, and
// exits non-zero on failure.
func Main(classes ...Class) {
	program := filepath.Base(os.Args[0])
	flags := flag.NewFlagSet(program, flag.ExitOnError)
	listen := flags.String("listen", "localhost:0",
		"where to serve: host:port (port 0 picks a free one) or unix:/path")
	register := flags.String("register", "",
		"address of a yarfd to register with, host:port or unix:/path (none when empty)")
	lease := flags.Uint("lease", 0, "registration lease to ask for, in seconds (0: yarfd's default)")
	flags.Usage = func() {
		fmt.Fprintf(flags.Output(), "usage: %s --listen ADDR [--register YARFD_ADDR] [--lease SECONDS]\n", program)
		flags.PrintDefaults()
	}
	flags.Parse(os.Args[1:])
	if flags.NArg() > 0 {
		flags.Usage()
		os.Exit(2)
	}
	err := Serve(Options{
		Listen:   *listen,
		Register: *register,
		Lease:    time.Duration(*lease) * time.Second,
		Classes:  classes,
	})
	if err != nil {
		fmt.Fprintf(os.Stderr, "%s: %v\n", program, err)
		os.Exit(1)
	}
}
