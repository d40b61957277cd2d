/* stack_image.c -- main() of the stack-analysis image: the library is
 * linked in whole (--whole-archive), nothing is called. */
int main(void);

int main(void) { return 0; }
