package component

import "fmt"

// The capabilities a class may declare (yarf.v1.ComponentInfo.capabilities):
// "sample_passes" for an Integrator that renders any range of sample
// passes and a crop window, "pixel_local" for a Transport whose samples
// land only in their own pixels (the farm may then render its jobs in
// tiles). yarfd refuses a registration naming another.
var capabilities = map[string]bool{"sample_passes": true, "pixel_local": true}

// WithCapabilities is the class declaring what it can do beyond its
// interfaces.
func (c Class) WithCapabilities(names ...string) Class {
	c.capabilities = append([]string(nil), names...)
	return c
}

func (c Class) checkCapabilities() error {
	for _, name := range c.capabilities {
		if !capabilities[name] {
			return fmt.Errorf("class %s declares an unknown capability %q", c.name, name)
		}
	}
	return nil
}
