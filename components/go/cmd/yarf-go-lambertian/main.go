// Command yarf-go-lambertian serves the go_lambertian surface model.
//
//	yarf-go-lambertian --listen ADDR [--register YARFD_ADDR] [--lease SECONDS]
package main

import (
	"yarf.dev/components/go/bsdf"
	"yarf.dev/components/go/component"
)

func main() {
	component.Main(bsdf.LambertianClass)
}
