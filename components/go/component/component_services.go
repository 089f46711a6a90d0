package component

import (
	"context"

	"google.golang.org/grpc/codes"
	"google.golang.org/grpc/status"
	yarfv1 "yarf.dev/components/go/gen/yarfv1"
)

// componentService answers yarf.v1.Component/Describe.
type componentService struct {
	yarfv1.UnimplementedComponentServer
	host *host
}

func (s *componentService) Describe(_ context.Context, request *yarfv1.DescribeRequest) (*yarfv1.ComponentInfo, error) {
	if handle := request.GetHandle(); handle != 0 {
		i, ok := s.host.instances.find(handle)
		if !ok {
			return nil, noInstance(handle)
		}
		return i.class.info(s.host.origin), nil
	}
	class, ok := s.host.byName[request.GetClassName()]
	if !ok {
		return nil, status.Errorf(codes.NotFound, "unknown component class '%s'", request.GetClassName())
	}
	return class.info(s.host.origin), nil
}

// factoryService answers yarf.v1.Factory.
type factoryService struct {
	yarfv1.UnimplementedFactoryServer
	host *host
}

func (s *factoryService) Create(_ context.Context, request *yarfv1.CreateRequest) (*yarfv1.CreateReply, error) {
	handle, info, err := s.host.create(request.GetClassName(), request.GetProperties())
	if err != nil {
		return nil, err
	}
	return &yarfv1.CreateReply{Handle: handle, Info: info}, nil
}

func (s *factoryService) Release(_ context.Context, request *yarfv1.ReleaseRequest) (*yarfv1.ReleaseReply, error) {
	if err := s.host.release(request.GetHandle()); err != nil {
		return nil, err
	}
	return &yarfv1.ReleaseReply{}, nil
}

// registryService answers yarf.v1.Registry for a component process: it
// lists its classes; loading plugins and taking registrations is yarfd's.
type registryService struct {
	yarfv1.UnimplementedRegistryServer
	host *host
}

func (s *registryService) ListClasses(context.Context, *yarfv1.ListClassesRequest) (*yarfv1.ListClassesReply, error) {
	reply := &yarfv1.ListClassesReply{}
	for i := range s.host.classes {
		reply.Classes = append(reply.Classes, s.host.classes[i].info(s.host.origin))
	}
	return reply, nil
}

func (s *registryService) LoadPlugin(context.Context, *yarfv1.LoadPluginRequest) (*yarfv1.LoadPluginReply, error) {
	return nil, status.Error(codes.Unimplemented, "a component process loads no plugins")
}

func (s *registryService) Register(context.Context, *yarfv1.RegisterRequest) (*yarfv1.RegisterReply, error) {
	return nil, status.Error(codes.Unimplemented, "a component process takes no registrations")
}

func (s *registryService) Unregister(context.Context, *yarfv1.UnregisterRequest) (*yarfv1.UnregisterReply, error) {
	return nil, status.Error(codes.Unimplemented, "a component process takes no registrations")
}
