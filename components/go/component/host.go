package component

import (
	"fmt"
	"strings"

	"google.golang.org/grpc/codes"
	"google.golang.org/grpc/status"
	yarfv1 "yarf.dev/components/go/gen/yarfv1"
)

// host is the state the services of one process share: the classes it
// serves and the instances made of them.
type host struct {
	classes   []Class
	byName    map[string]*Class
	origin    string
	instances instanceTable
}

func newHost(classes []Class, origin string) (*host, error) {
	if len(classes) == 0 {
		return nil, fmt.Errorf("no class to serve")
	}
	h := &host{classes: classes, byName: map[string]*Class{}, origin: origin}
	for i := range h.classes {
		class := &h.classes[i]
		if err := class.check(); err != nil {
			return nil, err
		}
		if _, taken := h.byName[class.name]; taken {
			return nil, fmt.Errorf("class %s is given twice", class.name)
		}
		h.byName[class.name] = class
	}
	return h, nil
}

// create makes an instance of the class `name`: NOT_FOUND for an unknown
// class, INVALID_ARGUMENT naming the property for bad properties.
func (h *host) create(name string, properties *yarfv1.Properties) (uint64, *yarfv1.ComponentInfo, error) {
	class, ok := h.byName[name]
	if !ok {
		return 0, nil, status.Errorf(codes.NotFound, "unknown component class '%s'", name)
	}
	props := NewProperties(properties)
	value, err := class.create(props)
	// A property error comes first: the constructor's own error may only
	// follow from it.
	if props.Err() != nil {
		err = props.Err()
	}
	if err != nil {
		return 0, nil, status.Errorf(codes.InvalidArgument, "component '%s': %v", name, err)
	}
	if unread := props.Unread(); len(unread) > 0 {
		closeValue(value)
		return 0, nil, status.Errorf(codes.InvalidArgument, "component '%s' does not understand property '%s'",
			name, strings.Join(unread, "', '"))
	}
	handle := h.instances.add(&instance{class: class, value: value})
	return handle, class.info(h.origin), nil
}

// release ends the instance `handle`; NOT_FOUND when there is none.
func (h *host) release(handle uint64) error {
	i, ok := h.instances.remove(handle)
	if !ok {
		return noInstance(handle)
	}
	i.close()
	return nil
}

// releaseAll ends every instance, at shutdown.
func (h *host) releaseAll() {
	for _, i := range h.instances.removeAll() {
		i.close()
	}
}

func closeValue(value any) { (&instance{value: value}).close() }

func noInstance(handle uint64) error {
	return status.Errorf(codes.NotFound, "no instance %d", handle)
}

// instanceAs finds the instance `handle` as interface I, whose full
// service name is iface: NOT_FOUND when there is none,
// FAILED_PRECONDITION when it does not implement I.
func instanceAs[I any](h *host, handle uint64, iface string) (I, error) {
	var typed I
	i, ok := h.instances.find(handle)
	if !ok {
		return typed, noInstance(handle)
	}
	typed, ok = i.value.(I)
	if !ok {
		return typed, status.Errorf(codes.FailedPrecondition, "instance %d ('%s') does not implement %s",
			handle, i.class.name, iface)
	}
	return typed, nil
}

// callError turns an error of an interface method or of its input into a
// status: gRPC status errors pass as they are, others are the caller's
// bad input.
func callError(iface string, err error) error {
	if _, ok := status.FromError(err); ok {
		return err
	}
	return status.Errorf(codes.InvalidArgument, "%s: %v", iface, err)
}
