// Command yarf-go-independent serves the go_independent sampler.
//
//	yarf-go-independent --listen ADDR [--register YARFD_ADDR] [--lease SECONDS]
package main

import (
	"yarf.dev/components/go/component"
	"yarf.dev/components/go/sampler"
)

func main() {
	component.Main(sampler.IndependentClass)
}
