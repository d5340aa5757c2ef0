program airlaunch
  implicit none
end program airlaunch
